/* SPDX-License-Identifier: Apache-2.0 */
/* STM32G031 reset cause: RCC_CSR flags as the hardware sets them for each
 * kind of reset (RM0444 §5.1.2: every internal reset also pulls NRST, so
 * PINRSTF comes along), plus the board's .noinit fault record and RAM-kept
 * marker, decoded to the hal's km_reset_cause_t. Each case names the reset
 * that produces those flags. */
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "g0_regs.h"
#include "reset_cause.h"

#define PIN RCC_CSR_PINRSTF

static void test_power_up(void **state)
{
    (void)state;
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_PWRRSTF | PIN, false, false), KM_RESET_POWER_ON);
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_PWRRSTF, false, false), KM_RESET_POWER_ON);
}

static void test_brownout_keeps_ram(void **state)
{
    (void)state;
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_PWRRSTF | PIN, false, true), KM_RESET_BROWNOUT);
}

static void test_power_outranks_everything(void **state)
{
    (void)state;
    /* After a power loss nothing in RAM is trusted, not even a fault record
     * that happens to look valid. */
    uint32_t all = RCC_CSR_RESET_FLAGS;
    assert_int_equal(g0_reset_cause_decode(all, true, false), KM_RESET_POWER_ON);
    assert_int_equal(g0_reset_cause_decode(all, true, true), KM_RESET_BROWNOUT);
}

static void test_pin_alone_is_the_pin(void **state)
{
    (void)state;
    assert_int_equal(g0_reset_cause_decode(PIN, false, true), KM_RESET_PIN);
    assert_int_equal(g0_reset_cause_decode(PIN, false, false), KM_RESET_PIN);
}

static void test_software_restart(void **state)
{
    (void)state;
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_SFTRSTF | PIN, false, true), KM_RESET_SOFTWARE);
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_SFTRSTF, false, true), KM_RESET_SOFTWARE);
}

static void test_fault_record_beats_sysresetreq(void **state)
{
    (void)state;
    /* The fault handler resets with SYSRESETREQ: hardware says software. */
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_SFTRSTF | PIN, true, true), KM_RESET_FAULT);
    /* A handler that ran but whose reset was then taken by the watchdog
     * (e.g. held off by a debugger) is still the fault's doing. */
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_IWDGRSTF | PIN, true, true), KM_RESET_FAULT);
}

static void test_watchdogs(void **state)
{
    (void)state;
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_IWDGRSTF | PIN, false, true), KM_RESET_WATCHDOG);
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_WWDGRSTF | PIN, false, true), KM_RESET_WATCHDOG);
    /* Flags from two resets (only if one came before the boot cleared
     * them): the watchdog is the more telling. */
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_IWDGRSTF | RCC_CSR_SFTRSTF | PIN, false, true),
                     KM_RESET_WATCHDOG);
}

static void test_low_power_and_option_load_are_other(void **state)
{
    (void)state;
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_LPWRRSTF | PIN, false, true), KM_RESET_OTHER);
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_OBLRSTF | PIN, false, true), KM_RESET_OTHER);
}

static void test_no_flag_reads_as_power_on(void **state)
{
    (void)state;
    /* The contract: POWER_ON also stands for "no flag the board can read"
     * (a debugger cleared them). Bits outside the reset flags do not count. */
    assert_int_equal(g0_reset_cause_decode(0u, false, true), KM_RESET_POWER_ON);
    assert_int_equal(g0_reset_cause_decode(RCC_CSR_RMVF | 3u, false, false), KM_RESET_POWER_ON);
}

static void test_every_single_flag_maps(void **state)
{
    (void)state;
    /* Each flag alone, with and without the record: never out of range. */
    for (uint32_t bit = 0u; bit < 32u; bit++) {
        for (int rec = 0; rec < 2; rec++) {
            for (int kept = 0; kept < 2; kept++) {
                km_reset_cause_t c = g0_reset_cause_decode(1u << bit, rec != 0, kept != 0);
                assert_true(c >= KM_RESET_POWER_ON && c <= KM_RESET_OTHER);
            }
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_power_up),
        cmocka_unit_test(test_brownout_keeps_ram),
        cmocka_unit_test(test_power_outranks_everything),
        cmocka_unit_test(test_pin_alone_is_the_pin),
        cmocka_unit_test(test_software_restart),
        cmocka_unit_test(test_fault_record_beats_sysresetreq),
        cmocka_unit_test(test_watchdogs),
        cmocka_unit_test(test_low_power_and_option_load_are_other),
        cmocka_unit_test(test_no_flag_reads_as_power_on),
        cmocka_unit_test(test_every_single_flag_maps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
