/* SPDX-License-Identifier: Apache-2.0 */
/* The dispatcher as the 32 KiB STM32G031F6 build compiles it
 * (KM_FEATURE_MULTI_READ=0: no multi-ID read 0x82, docs/footprint.md "What
 * gives way"): docs/protocol.md §3 leaves 0x82 "to be completed", so
 * without this firmware's definition it is a command the servo does not
 * support, answered exactly as 0x7E (factory test, not provided) is:
 * status bit 5 (§4: "command exception: ... command/address not
 * supported"), no answer, nothing else changes, the next ping reports it
 * once; at the super ID nothing at all. A broadcast 0x82 that lists this
 * servo gets no answer. Built from protocol/km_servo.c with the feature
 * off, the rest of the protocol library as it is. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_test_support.h"

#define ID 7
static kt_fx_t fx;
static kt_fx_t fx_7e; /* the same servo, sent 0x7E instead */

_Static_assert(KM_FEATURE_MULTI_READ == 0, "this test is built with the multi-ID read compiled out");

/* A servo that answers writes (response level 1), so a write would show. */
static void prv_init(kt_fx_t *f)
{
    kt_init(f, kt_product_pot(), ID);
    kt_write_u8(f, ID, 0x11, 0x0A);
    kt_reply_is_status(f, ID, 0);
}

/* 0x82 with body to `id`: no answer (at the broadcast ID
 * km_servo_may_answer() false), the state after it exactly that after 0x7E
 * with the same body, and the unreported bits `want_bits`, which the next
 * ping reports once. */
static void prv_unsupported(uint8_t id, const uint8_t *body, unsigned n, uint8_t want_bits)
{
    prv_init(&fx);
    prv_init(&fx_7e);
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    const km_frame_view_t v = {.id = id, .cmd = 0x82, .body_len = (uint8_t)n, .body = body, .end_tick = 0};
    if (id == KM_ID_BROADCAST) {
        assert_false(km_servo_may_answer(&fx.s, &v)); /* the application keeps its answer buffer */
    }
    kt_send(&fx, id, 0x82, body, n);
    kt_no_reply(&fx);
    kt_send(&fx_7e, id, 0x7E, body, n);
    kt_no_reply(&fx_7e);
    kt_snap_t as_7e;
    kt_snap(&fx_7e, &as_7e);
    kt_assert_unchanged(&fx, &as_7e);
    sn.unreported |= want_bits;
    kt_assert_unchanged(&fx, &sn);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, want_bits);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, 0);
}

/* §3/§4: 0x82 to the servo's own ID, with a list holding it, one
 * without it and no body: bit 5, no answer, as 0x7E. */
static void test_0x82_to_own_id_is_an_unsupported_command(void **state)
{
    (void)state;
    static const uint8_t k_listed[] = {0x01, ID};
    static const uint8_t k_unlisted[] = {0x46, 3, 9};
    prv_unsupported(ID, k_listed, sizeof k_listed, KM_ST_EXCEPTION);
    prv_unsupported(ID, k_unlisted, sizeof k_unlisted, KM_ST_EXCEPTION);
    prv_unsupported(ID, NULL, 0u, KM_ST_EXCEPTION);
}

/* §1/§3: a broadcast 0x82 is executed by every servo and, the command
 * being unsupported, answered by none, even one it lists first, last or
 * alone: bit 5, as a broadcast 0x7E. */
static void test_0x82_broadcast_listing_this_servo_not_answered(void **state)
{
    (void)state;
    static const uint8_t k_alone[] = {0x01, ID};
    static const uint8_t k_first[] = {0x46, ID, 1, 2};
    static const uint8_t k_last[] = {0x38, 1, 2, 3, ID};
    static const uint8_t k_unlisted[] = {0x46, 1, 2, 3};
    prv_unsupported(KM_ID_BROADCAST, k_alone, sizeof k_alone, KM_ST_EXCEPTION);
    prv_unsupported(KM_ID_BROADCAST, k_first, sizeof k_first, KM_ST_EXCEPTION);
    prv_unsupported(KM_ID_BROADCAST, k_last, sizeof k_last, KM_ST_EXCEPTION);
    prv_unsupported(KM_ID_BROADCAST, k_unlisted, sizeof k_unlisted, KM_ST_EXCEPTION);
}

/* §3 "Super ID": only queries answer there; 0x82 to it changes nothing,
 * as 0x7E. */
static void test_0x82_super_id_ignored(void **state)
{
    (void)state;
    static const uint8_t k_listed[] = {0x01, ID};
    prv_unsupported(KM_ID_SUPER, k_listed, sizeof k_listed, 0u);
}

/* The protocol's own commands still answer: ping and a read of 0x0F. */
static void test_spec_commands_still_answer(void **state)
{
    (void)state;
    prv_init(&fx);
    kt_spec_commands_answer(&fx, ID);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_0x82_to_own_id_is_an_unsupported_command),
        cmocka_unit_test(test_0x82_broadcast_listing_this_servo_not_answered),
        cmocka_unit_test(test_0x82_super_id_ignored),
        cmocka_unit_test(test_spec_commands_still_answer),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
