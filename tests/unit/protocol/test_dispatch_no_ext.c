/* SPDX-License-Identifier: Apache-2.0 */
/* The dispatcher as the 32 KiB STM32G031F6 build compiles it
 * (KM_FEATURE_EXT=0: no extension command 0x7F, docs/footprint.md "What
 * gives way"): 0x7F is answered as docs/protocol.md answers a command it
 * does not support, the same way 0x7E (factory test, not provided) is:
 * status bit 5 (§4: "command exception: ... command/address not
 * supported"), no answer, nothing else changes, the next ping reports it
 * once; at the super ID and broadcast no answer either. Every command of
 * docs/protocol.md §3 still answers. Built from protocol/km_servo.c with
 * the feature off, the rest of the protocol library as it is. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_test_support.h"

#define ID 7
static kt_fx_t fx;

_Static_assert(KM_FEATURE_EXT == 0, "this test is built with the extension command compiled out");

/* A servo that answers writes (response level 1), so a write would show. */
static void prv_init(void)
{
    kt_init(&fx, kt_product_pot(), ID);
    kt_write_u8(&fx, ID, 0x11, 0x0A);
    kt_reply_is_status(&fx, ID, 0);
}

/* One frame of cmd with body to our ID: bit 5, no answer, no other change,
 * reported by the next ping once. */
static void prv_unsupported(uint8_t cmd, const uint8_t *body, unsigned n)
{
    prv_init();
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_send(&fx, ID, cmd, body, n);
    kt_no_reply(&fx);
    sn.unreported |= KM_ST_EXCEPTION;
    kt_assert_unchanged(&fx, &sn);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, 0);
}

/* §3/§4: 0x7F of each address the 64 KiB build answers (0x01-0x03, the
 * fault log's 0x10 and 0x11), of one it never had, and with no address:
 * exactly as 0x7E. */
static void test_0x7F_is_an_unsupported_command(void **state)
{
    (void)state;
    static const uint8_t k_addrs[] = {0x01, 0x02, 0x03, 0x10, 0x11, 0x20, 0x7F};
    for (size_t i = 0; i < sizeof k_addrs; i++) {
        prv_unsupported(0x7F, &k_addrs[i], 1u);
        prv_unsupported(0x7E, &k_addrs[i], 1u);
    }
    prv_unsupported(0x7F, NULL, 0u);
}

/* §1: at the super ID and broadcast 0x7F is not answered (a query the
 * servo does not have gets no slot). */
static void test_0x7F_super_and_broadcast_silent(void **state)
{
    (void)state;
    static const uint8_t k_addr = 0x01;
    prv_init();
    kt_send(&fx, KM_ID_SUPER, 0x7F, &k_addr, 1u);
    kt_no_reply(&fx);
    kt_send(&fx, KM_ID_BROADCAST, 0x7F, &k_addr, 1u);
    kt_no_reply(&fx);
}

/* The protocol's own commands still answer: ping and a read of 0x0F. */
static void test_spec_commands_still_answer(void **state)
{
    (void)state;
    prv_init();
    kt_spec_commands_answer(&fx, ID);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_0x7F_is_an_unsupported_command),
        cmocka_unit_test(test_0x7F_super_and_broadcast_silent),
        cmocka_unit_test(test_spec_commands_still_answer),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
