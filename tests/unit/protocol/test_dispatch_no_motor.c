/* SPDX-License-Identifier: Apache-2.0 */
/* The dispatcher as the 32 KiB STM32G031F6 build compiles it without motor
 * mode (KM_FEATURE_MOTOR_MODE=0, docs/footprint.md "What gives way"):
 * 0x6E and 0x70 answer exactly as a reserved address does (docs/protocol.md
 * §4: status bit 5, "command/address not supported"), through every command
 * that carries an address (0x02, 0x03, 0x04/0x84, 0x82, 0x83), at the
 * servo's ID, the super ID and broadcast; a write of 0x5A = 2 is refused
 * exactly as the out-of-range 0x5A = 3 (bit 6, nothing changes). Each frame
 * goes to two servos, one with the motor address and one with the reserved
 * 0x69 (or 0x5A = 3), and their answers and states must be the same.
 * Control (a fake recording requests) never hears of a motor run. Built
 * against protocol/ compiled with the feature off
 * (tests/unit/protocol/CMakeLists.txt). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_test_support.h"

#define ID 7
#define RESERVED 0x69u /* between 0x68 and 0x6E: no register (§5.4) */

_Static_assert(KM_FEATURE_MOTOR_MODE == 0, "this test is built with motor mode compiled out");

static kt_fx_t fx_motor; /* gets the motor address */
static kt_fx_t fx_twin;  /* gets the reserved address (or the out-of-range value) */

/* A potentiometer servo that answers writes (response level 1), torque on. */
static void prv_init(kt_fx_t *fx)
{
    kt_init(fx, kt_product_pot(), ID);
    kt_write_u8(fx, ID, 0x11, 0x0A);
    kt_reply_is_status(fx, ID, 0);
    kt_write_u8(fx, ID, 0x64, 2);
    kt_reply_is_status(fx, ID, 0);
    fx->fake.n_requests = 0u;
}

/* Both servos answered the same bytes, are in the same state, and control
 * got no request from either. */
static void prv_same(void)
{
    assert_int_equal(fx_motor.reply.len, fx_twin.reply.len);
    assert_memory_equal(fx_motor.reply.bytes, fx_twin.reply.bytes, fx_motor.reply.len);
    kt_snap_t a, b;
    kt_snap(&fx_motor, &a);
    kt_snap(&fx_twin, &b);
    kt_assert_unchanged(&fx_motor, &b);
    assert_memory_equal(&a, &b, sizeof a);
    assert_int_equal(fx_motor.fake.n_requests, 0u);
}

/* Frame `cmd` to `id` with `body`, its first byte `addr` on one servo and
 * `twin_addr` on the other; then a ping of each (what they report). */
static void prv_send_both(uint8_t id, uint8_t cmd, const uint8_t *body, unsigned n, uint8_t twin_body0)
{
    uint8_t twin[KM_BODY_MAX];
    if (n > 0u) { /* a body-less frame (0x84) is the same on both */
        memcpy(twin, body, n);
        twin[0] = twin_body0;
    }
    kt_send(&fx_motor, id, cmd, body, n);
    kt_send(&fx_twin, id, cmd, twin, n);
    prv_same();
    kt_ping(&fx_motor, ID);
    kt_ping(&fx_twin, ID);
    prv_same();
}

/* A write of `addr` with its value bytes, as 0x03 to every ID kind, as a
 * sync write executed by 0x84, and as an 0x83 entry: as at RESERVED. */
static void prv_write_as_reserved(const uint8_t *body, unsigned n)
{
    static const uint8_t k_ids[] = {ID, KM_ID_SUPER, KM_ID_BROADCAST};
    for (size_t i = 0; i < sizeof k_ids; i++) {
        prv_init(&fx_motor);
        prv_init(&fx_twin);
        prv_send_both(k_ids[i], 0x03, body, n, RESERVED);
    }
    prv_init(&fx_motor);
    prv_init(&fx_twin);
    prv_send_both(ID, 0x04, body, n, RESERVED);
    prv_send_both(KM_ID_BROADCAST, 0x84, NULL, 0u, 0u);
    uint8_t multi[KM_BODY_MAX];
    multi[0] = body[0];
    multi[1] = (uint8_t)(n - 1u);
    multi[2] = ID;
    memcpy(&multi[3], &body[1], n - 1u);
    prv_init(&fx_motor);
    prv_init(&fx_twin);
    prv_send_both(KM_ID_BROADCAST, 0x83, multi, n + 2u, RESERVED);
}

/* §5.4 0x6E (PWM 500, and -1000) and 0x70 (run on at PWM 500; for 2 s at
 * 800, braked after): not in this build, so no motor runs and every
 * command answers as at a reserved address. */
static void test_motor_writes_answer_as_reserved(void **state)
{
    (void)state;
    static const uint8_t k_6e_500[] = {0x6E, 0xF4, 0x01};
    static const uint8_t k_6e_neg[] = {0x6E, 0x18, 0xFC};
    static const uint8_t k_70_on[] = {0x70, 0x00, 0x00, 0x00, 0xF4, 0x01};
    static const uint8_t k_70_time[] = {0x70, 0x12, 0x14, 0x00, 0x20, 0x03};
    prv_write_as_reserved(k_6e_500, sizeof k_6e_500);
    prv_write_as_reserved(k_6e_neg, sizeof k_6e_neg);
    prv_write_as_reserved(k_70_on, sizeof k_70_on);
    prv_write_as_reserved(k_70_time, sizeof k_70_time);
}

/* §4 spelled out for the servo's own ID: the write's answer carries bit 5
 * and nothing else, the next ping reports it once. */
static void test_motor_write_is_bit5(void **state)
{
    (void)state;
    static const uint8_t k_70_on[] = {0x00, 0x00, 0x00, 0xF4, 0x01};
    prv_init(&fx_motor);
    kt_write_u16(&fx_motor, ID, 0x6E, 500u);
    kt_reply_is_status(&fx_motor, ID, KM_ST_EXCEPTION);
    kt_write(&fx_motor, ID, 0x70, k_70_on, sizeof k_70_on);
    kt_reply_is_status(&fx_motor, ID, KM_ST_EXCEPTION);
    assert_int_equal(fx_motor.fake.n_requests, 0u);
    kt_ping_is(&fx_motor, ID, 0);
}

/* Reads of 0x6E and 0x70 (0x02 at each ID kind, 0x82): as of RESERVED. */
static void test_motor_reads_answer_as_reserved(void **state)
{
    (void)state;
    static const uint8_t k_ids[] = {ID, KM_ID_SUPER, KM_ID_BROADCAST};
    static const uint8_t k_addrs[] = {0x6E, 0x70};
    for (size_t a = 0; a < sizeof k_addrs; a++) {
        for (size_t i = 0; i < sizeof k_ids; i++) {
            prv_init(&fx_motor);
            prv_init(&fx_twin);
            prv_send_both(k_ids[i], 0x02, &k_addrs[a], 1u, RESERVED);
        }
        const uint8_t multi[] = {k_addrs[a], 3, ID, 9};
        prv_init(&fx_motor);
        prv_init(&fx_twin);
        prv_send_both(KM_ID_BROADCAST, 0x82, multi, sizeof multi, RESERVED);
    }
}

/* §5.4 0x5A = 2 (motor only) is out of range here: refused as 0x5A = 3 is
 * (bit 6, 0x5A stays), by 0x03 at each ID kind and by 0x04/0x84. */
static void test_0x5A_2_refused_as_out_of_range(void **state)
{
    (void)state;
    static const uint8_t k_ids[] = {ID, KM_ID_SUPER, KM_ID_BROADCAST};
    for (size_t i = 0; i < sizeof k_ids; i++) {
        prv_init(&fx_motor);
        prv_init(&fx_twin);
        kt_write_u8(&fx_motor, k_ids[i], 0x5A, 2);
        kt_write_u8(&fx_twin, k_ids[i], 0x5A, 3);
        prv_same();
        kt_ping(&fx_motor, ID);
        kt_ping(&fx_twin, ID);
        prv_same();
    }
    prv_init(&fx_motor);
    kt_write_u8(&fx_motor, ID, 0x5A, 2);
    kt_reply_is_status(&fx_motor, ID, KM_ST_FAILED);
    kt_read(&fx_motor, ID, 0x5A);
    assert_int_equal(kt_read_le(&fx_motor, 0x5A), 0u);
    static const uint8_t k_sync[] = {0x5A, 2};
    kt_send(&fx_motor, ID, 0x04, k_sync, sizeof k_sync);
    kt_send(&fx_motor, KM_ID_BROADCAST, 0x84, NULL, 0u);
    kt_read(&fx_motor, ID, 0x5A);
    assert_int_equal(kt_read_le(&fx_motor, 0x5A), 0u);
}

/* What stays: 0x5A = 1 and 0 are taken, 0x6F fails with bit 6 as on any
 * potentiometer product (§6), and a servo move still reaches control. */
static void test_servo_mode_and_0x5A_1_stay(void **state)
{
    (void)state;
    prv_init(&fx_motor);
    kt_write_u8(&fx_motor, ID, 0x5A, 1);
    kt_reply_is_status(&fx_motor, ID, 0);
    kt_read(&fx_motor, ID, 0x5A);
    assert_int_equal(kt_read_le(&fx_motor, 0x5A), 1u);
    kt_write_u8(&fx_motor, ID, 0x5A, 0);
    kt_reply_is_status(&fx_motor, ID, 0);
    kt_write_u16(&fx_motor, ID, 0x6F, 100u);
    kt_reply_is_status(&fx_motor, ID, KM_ST_FAILED);
    assert_int_equal(fx_motor.fake.n_requests, 0u);
    kt_write_u16(&fx_motor, ID, 0x65, 300u);
    kt_reply_is_status(&fx_motor, ID, 0);
    assert_int_equal(fx_motor.fake.n_requests, 1u);
    assert_int_equal(fx_motor.fake.requests[0].kind, KM_REQ_MOVE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_motor_writes_answer_as_reserved),
        cmocka_unit_test(test_motor_write_is_bit5),
        cmocka_unit_test(test_motor_reads_answer_as_reserved),
        cmocka_unit_test(test_0x5A_2_refused_as_out_of_range),
        cmocka_unit_test(test_servo_mode_and_0x5A_1_stay),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
