/* SPDX-License-Identifier: Apache-2.0 */
/* docs/protocol.md §3 sync write (0x04/0x84) and multi-ID write (0x83) beyond the
 * §2 worked frames: value checks at execute time, who clears the buffer,
 * which servos' status bits a 0x83 touches. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_test_support.h"

#define ID 4
static kt_fx_t fx;

/* "Sync write": the value is checked when 0x84 runs it: a bad value is
 * buffered, then refused with bit 6 at execute, nothing changes. */
static void test_s3_sync_write_value_checked_at_execute(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t body[] = {0x13, 0xE9, 0x03}; /* 1001 */
    kt_send(&fx, ID, 0x04, body, sizeof body);
    kt_no_reply(&fx);
    assert_int_equal(km_servo_status(&fx.s), 0);
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    sn.sync_full = false;          /* executing empties the buffer */
    sn.unreported |= KM_ST_FAILED; /* 0x84 has no answer: the next ping reports it */
    kt_send_hex(&fx, "F9 FF FE 02 84 7B");
    kt_assert_unchanged(&fx, &sn);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    kt_ping_is(&fx, ID, 0);
}

/* Sync write of a persisted register: committed at execute, not before. */
static void test_s3_sync_write_commits_at_execute(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t body[] = {0x13, 0xF4, 0x01}; /* 500 */
    kt_send(&fx, ID, 0x04, body, sizeof body);
    assert_int_equal(fx.fake.n_commits, 0);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_MAX_TORQUE), 1000);
    kt_send(&fx, ID, 0x84, NULL, 0); /* 0x84 to the own ID works too */
    kt_no_reply(&fx);
    assert_int_equal(fx.fake.n_commits, 1);
    assert_int_equal(kt_commit_value(&fx.fake.commits[0], 0x13), 500);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_MAX_TORQUE), 500);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_LIMIT), 500);
}

/* "Sync write": 0x04 is for one target ID: sent broadcast it is refused
 * with bit 5; sent to the super ID it is ignored. */
static void test_s3_sync_write_broadcast_and_super(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t body[] = {0x64, 0x02};
    kt_send(&fx, KM_ID_BROADCAST, 0x04, body, sizeof body);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION);
    assert_false(fx.s.sync.full);
    kt_send(&fx, KM_ID_SUPER, 0x04, body, sizeof body);
    assert_false(fx.s.sync.full);
    kt_send_hex(&fx, "F9 FF FE 02 84 7B");
    assert_int_equal(fx.fake.n_requests, 0);
}

/* 0x84 with parameters: malformed, bit 5, the buffer is dropped. */
static void test_s3_sync_execute_with_parameters(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t body[] = {0x64, 0x02};
    kt_send(&fx, ID, 0x04, body, sizeof body);
    const uint8_t extra[] = {0x00};
    kt_send(&fx, KM_ID_BROADCAST, 0x84, extra, 1);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION);
    assert_int_equal(fx.fake.n_requests, 0);
    kt_send_hex(&fx, "F9 FF FE 02 84 7B");
    assert_int_equal(fx.fake.n_requests, 0);
}

/* A 0x04 longer than any register's write: bit 6, nothing buffered. */
static void test_s3_sync_write_too_long(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    uint8_t body[12] = {0x65};
    kt_send(&fx, ID, 0x04, body, sizeof body);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
    assert_false(fx.s.sync.full);
}

/* Restart through sync write: executes at 0x84, no answer. */
static void test_s3_sync_write_restart(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_send_hex(&fx, "F9 FF 04 07 04 02 E1 E2 E3 E4 64");
    assert_int_equal(fx.fake.restarts, 0);
    kt_send_hex(&fx, "F9 FF FE 02 84 7B");
    assert_int_equal(fx.fake.restarts, 1);
}

#define NSERVO 6
static kt_fx_t bus[NSERVO];

/* "Multi-ID write" with "One life cycle for bits 5 and 6": an 0x83 gets no
 * answer, so a listed servo adds its entry's outcome to the unreported bits
 * and keeps the earlier ones; servos not listed change nothing. Every
 * allowed address reaches its request. */
static void test_s3_multi_id_status_bits_and_addresses(void **state)
{
    (void)state;
    for (uint8_t i = 0; i < NSERVO; i++) {
        kt_init(&bus[i], kt_product_enc(), i);
        km_servo_note_checksum_error(&bus[i].s); /* bit 5 unreported everywhere */
    }
    /* 0x64 to servo 1 (valid 2) and 2 (invalid 7) */
    const uint8_t b1[] = {0x64, 0x01, 1, 0x02, 2, 0x07};
    for (uint8_t i = 0; i < NSERVO; i++) {
        kt_send(&bus[i], KM_ID_BROADCAST, 0x83, b1, sizeof b1);
        kt_no_reply(&bus[i]);
    }
    assert_int_equal(bus[1].fake.n_requests, 1);
    assert_int_equal(bus[2].fake.n_requests, 0);
    assert_int_equal(km_servo_reg(&bus[2].s, KM_REG_TORQUE_SWITCH), 3);
    for (uint8_t i = 0; i < NSERVO; i++) {
        /* servo 2's failed entry joins the earlier bit 5; the rest keep theirs */
        const uint8_t want = i == 2 ? KM_ST_EXCEPTION | KM_ST_FAILED : KM_ST_EXCEPTION;
        kt_ping_is(&bus[i], i, want);
        kt_ping_is(&bus[i], i, 0);
    }
    static const struct {
        uint8_t addr;
        km_request_kind_t kind;
        uint8_t how;
    } allowed[] = {
        {0x66, KM_REQ_MOVE, KM_MOVE_SPEED},
        {0x68, KM_REQ_MOVE, KM_MOVE_STREAM},
        {0x6E, KM_REQ_MOTOR, KM_RUN_PWM},
        {0x6F, KM_REQ_MOTOR, KM_RUN_SPEED},
    };
    for (unsigned a = 0; a < 4; a++) {
        kt_init(&bus[3], kt_product_enc(), 3);
        const uint8_t b[] = {allowed[a].addr, 0x02, 0x01, 0x11, 0x00, 0x03, 0x64, 0x00};
        kt_send(&bus[3], KM_ID_BROADCAST, 0x83, b, sizeof b);
        assert_int_equal(bus[3].fake.n_requests, 1);
        assert_int_equal(bus[3].fake.requests[0].kind, allowed[a].kind);
        if (allowed[a].kind == KM_REQ_MOTOR) {
            assert_int_equal(bus[3].fake.requests[0].u.run.mode, allowed[a].how);
            assert_false(bus[3].fake.requests[0].u.run.reverse);
            assert_int_equal(bus[3].fake.requests[0].u.run.value, 100);
        } else {
            assert_int_equal(bus[3].fake.requests[0].u.move.kind, allowed[a].how);
            assert_int_equal(bus[3].fake.requests[0].u.move.target, 100);
        }
    }
}

/* A multi-ID write to a listed servo clears its sync buffer (a command to it). */
static void test_s3_multi_id_clears_sync_buffer_of_listed_only(void **state)
{
    (void)state;
    kt_init(&bus[0], kt_product_pot(), 1);
    kt_init(&bus[1], kt_product_pot(), 2);
    const uint8_t s1[] = {0x13, 0xF4, 0x01};
    kt_send(&bus[0], 1, 0x04, s1, sizeof s1);
    kt_send(&bus[1], 2, 0x04, s1, sizeof s1);
    const uint8_t m[] = {0x64, 0x01, 1, 0x02};
    kt_send(&bus[0], KM_ID_BROADCAST, 0x83, m, sizeof m);
    kt_send(&bus[1], KM_ID_BROADCAST, 0x83, m, sizeof m);
    kt_send_hex(&bus[0], "F9 FF FE 02 84 7B");
    kt_send_hex(&bus[1], "F9 FF FE 02 84 7B");
    assert_int_equal(km_servo_reg(&bus[0].s, KM_REG_MAX_TORQUE), 1000);
    assert_int_equal(km_servo_reg(&bus[1].s, KM_REG_MAX_TORQUE), 500);
}

/* "Multi-ID write": a servo listed twice runs its first entry only; an 0x83
 * sent to the super ID or another servo's ID is ignored (bits kept). */
static void test_s3_multi_id_first_entry_and_non_broadcast(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t twice[] = {0x64, 0x01, ID, 0x01, ID, 0x02};
    kt_send(&fx, KM_ID_BROADCAST, 0x83, twice, sizeof twice);
    assert_int_equal(fx.fake.n_requests, 1);
    assert_int_equal(fx.fake.requests[0].u.torque, 1);
    kt_write_u8(&fx, ID, 0x64, 9); /* bit 6 pending */
    const uint8_t m[] = {0x64, 0x01, ID, 0x02};
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_send(&fx, KM_ID_SUPER, 0x83, m, sizeof m);
    kt_send(&fx, ID + 1, 0x83, m, sizeof m);
    kt_no_reply(&fx);
    kt_assert_unchanged(&fx, &sn);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s3_sync_write_value_checked_at_execute),
        cmocka_unit_test(test_s3_sync_write_commits_at_execute),
        cmocka_unit_test(test_s3_sync_write_broadcast_and_super),
        cmocka_unit_test(test_s3_sync_execute_with_parameters),
        cmocka_unit_test(test_s3_sync_write_too_long),
        cmocka_unit_test(test_s3_sync_write_restart),
        cmocka_unit_test(test_s3_multi_id_status_bits_and_addresses),
        cmocka_unit_test(test_s3_multi_id_clears_sync_buffer_of_listed_only),
        cmocka_unit_test(test_s3_multi_id_first_entry_and_non_broadcast),
    };
    return cmocka_run_group_tests_name("dispatch_sync_multi", tests, NULL, NULL);
}
