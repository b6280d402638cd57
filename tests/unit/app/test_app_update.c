/* SPDX-License-Identifier: Apache-2.0 */
/* 0x78 in the application (docs/update.md §4, application column), through
 * the real main loop on the fake board: STATUS answers state 0, ENTER
 * restarts into the bootloader when the board has one (nothing after it
 * runs) and is refused with bit 5 when it has none, every other
 * sub-command is bit 5, broadcast is never answered. And the trial (§3a):
 * the start is confirmed to the bootloader once per boot, after the main
 * loop has served the bus for 1 s, not before. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "km_app.h"
#include "km_fake_hal.h"
#include "km_test_support.h"

/* This test's board: a bootloader present or not, and what it was asked. */
static bool s_has_bootloader;
static unsigned s_requests;
static unsigned s_confirms;     /* km_board_boot_confirm() calls */
static uint32_t s_confirm_now;  /* virtual time of the last one */
static unsigned s_confirm_boot; /* kf_world.boots then */

void km_board_boot_confirm(void)
{
    s_confirms++;
    s_confirm_now = kf_world.now;
    s_confirm_boot = kf_world.boots;
}

static uint8_t s_request_id; /* what the last request handed over */
static uint32_t s_request_baud;

bool km_board_boot_request(uint8_t id, uint32_t baud)
{
    if (!s_has_bootloader) {
        return false;
    }
    s_requests++;
    s_request_id = id;
    s_request_baud = baud;
    return true;
}

static void prv_send(const char *hex)
{
    kf_send_hex(hex);
    assert_true(kf_run_for(30000u));
}

static void prv_answered(const char *hex)
{
    uint8_t want[128], got[512];
    const unsigned n = kt_hex(hex, want, sizeof want);
    const unsigned m = kf_take_tx(got, sizeof got);
    assert_int_equal(m, n);
    assert_memory_equal(got, want, n);
}

static int prv_setup(void **state)
{
    (void)state;
    s_has_bootloader = false;
    s_requests = 0u;
    s_confirms = 0u;
    kf_power_on();
    assert_true(kf_run_for(20000u));
    uint8_t drop[64];
    while (kf_take_tx(drop, sizeof drop) > 0u) {
    }
    return 0;
}

/* STATUS to our ID (0): state 0 "application running", no session. */
static void test_status_says_application(void **state)
{
    (void)state;
    prv_send("F9 FF 00 05 78 04 00 00 7E");
    prv_answered("F9 F5 00 0B 78 04 00 00 00 00 00 00 00 00 78");
    prv_send("F9 FF FE 05 78 04 00 00 80"); /* broadcast: never answered */
    prv_answered("");
}

/* No bootloader: ENTER is refused with bit 5, nothing restarts. */
static void test_enter_without_bootloader_is_bit5(void **state)
{
    (void)state;
    prv_send("F9 FF 00 07 78 01 B1 B2 B3 B4 B5");
    prv_answered("F9 F5 00 02 20 DD");
    assert_int_equal(s_requests, 0);
}

/* A bootloader: ENTER leaves the request and restarts at once, without an
 * answer; a ping in the same write never runs (docs/protocol-decisions.md
 * "Restart"), the servo answers again after the restart. */
static void test_enter_with_bootloader_restarts(void **state)
{
    (void)state;
    s_has_bootloader = true;
    const uint32_t boots = kf_world.boots;
    /* Both frames received when the loop gets to them (one tick for all). */
    uint8_t b[32];
    const unsigned n = kt_hex("F9 FF 00 07 78 01 B1 B2 B3 B4 B5 F9 FF 00 02 01 FC", b, sizeof b);
    kf_send_burst_at(kf_world.now, b, n);
    assert_true(kf_run_for(30000u));
    assert_int_equal(s_requests, 1);
    assert_int_equal(kf_world.software_resets, 1);
    assert_int_equal(kf_world.boots, boots + 1u);
    prv_answered("");
    prv_send("F9 FF 00 02 01 FC");
    prv_answered("F9 F5 00 02 00 FD");
}

/* ENTER hands the bootloader the ID and baud the servo answers on
 * (docs/update.md §3: update mode answers there): ID 5 after a write of
 * 0x0F, the baud the bus was opened at. */
static void test_enter_hands_over_id_and_baud(void **state)
{
    (void)state;
    s_has_bootloader = true;
    prv_send("F9 FF 00 04 03 0F 05 E4"); /* ID 0 -> 5 */
    uint8_t drop[64];
    while (kf_take_tx(drop, sizeof drop) > 0u) {
    }
    prv_send("F9 FF 05 07 78 01 B1 B2 B3 B4 B0");
    assert_int_equal(s_requests, 1);
    assert_int_equal(s_request_id, 5);
    assert_int_equal(s_request_baud, kf_world.baud);
    assert_int_equal(kf_world.baud, 115200);
}

/* Bad magic, the bootloader's sub-commands, an unknown one, none: bit 5. */
static void test_other_sub_commands_bit5(void **state)
{
    (void)state;
    s_has_bootloader = true;
    static const char *const frames[] = {
        "F9 FF 00 07 78 01 B1 B2 B3 B5 B4", /* ENTER, bad magic */
        "F9 FF 00 03 78 05 7F",             /* VERIFY */
        "F9 FF 00 03 78 06 7E",             /* COMMIT */
        "F9 FF 00 07 78 07 E1 E2 E3 E4 EF", /* START */
        "F9 FF 00 03 78 09 7B",             /* unknown */
        "F9 FF 00 02 78 85",                /* no sub-command */
    };
    for (size_t i = 0; i < sizeof frames / sizeof frames[0]; i++) {
        prv_send(frames[i]);
        prv_answered("F9 F5 00 02 20 DD");
    }
    assert_int_equal(s_requests, 0);
}

/* §3a: booted at 1000 us (kf_power_on), the app serves the bus and
 * confirms its start once, 1 s after its init; a restart boots it again,
 * which confirms again 1 s later. */
static void test_start_confirmed_after_one_second(void **state)
{
    (void)state;
    assert_true(kf_run_until(1000u + 990000u));
    assert_int_equal(s_confirms, 0);
    prv_send("F9 FF 00 02 01 FC"); /* it serves the bus meanwhile */
    prv_answered("F9 F5 00 02 00 FD");
    assert_true(kf_run_until(1000u + 1010000u));
    assert_int_equal(s_confirms, 1);
    assert_in_range(s_confirm_now - 1000u, 1000000u, 1002000u);
    assert_true(kf_run_for(3000000u));
    assert_int_equal(s_confirms, 1);
    const unsigned boots = kf_world.boots;
    const uint32_t sent = kf_world.now;
    prv_send("F9 FF 00 07 03 02 E1 E2 E3 E4 69"); /* the standard restart */
    assert_int_equal(kf_world.boots, boots + 1u);
    assert_true(kf_run_until(sent + 900000u));
    assert_int_equal(s_confirms, 1);
    assert_true(kf_run_until(sent + 1100000u));
    assert_int_equal(s_confirms, 2);
    assert_int_equal(s_confirm_boot, boots + 1u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_status_says_application, prv_setup),
        cmocka_unit_test_setup(test_enter_without_bootloader_is_bit5, prv_setup),
        cmocka_unit_test_setup(test_enter_with_bootloader_restarts, prv_setup),
        cmocka_unit_test_setup(test_enter_hands_over_id_and_baud, prv_setup),
        cmocka_unit_test_setup(test_other_sub_commands_bit5, prv_setup),
        cmocka_unit_test_setup(test_start_confirmed_after_one_second, prv_setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
