/* SPDX-License-Identifier: Apache-2.0 */
/* Every worked frame of docs/protocol.md §2 through the dispatcher: the frames are
 * checksum-checked by kt_frame_from_hex(), and every answer is compared byte
 * for byte with the one printed in §2 (or built from the §2 rule). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_test_support.h"

static kt_fx_t fx;

/* §2 "ping ID 1 F9 FF 01 02 01 FB" -> "F9 F5 01 02 00 FC" */
static void test_s2_ping_worked_frame(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    kt_send_hex(&fx, "F9 FF 01 02 01 FB");
    kt_reply_is_hex(&fx, "F9 F5 01 02 00 FC");
    assert_int_equal(fx.reply.delay_us, 200); /* §5.1 0x12 default */
}

/* §2 "read protocol version, ID 1 F9 FF 01 03 02 0B EE": value 0x05020000 LE. */
static void test_s2_read_protocol_version_worked_frame(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    kt_send_hex(&fx, "F9 FF 01 03 02 0B EE");
    /* F9 F5 01 07 02 0B 00 00 02 05 cs; cs = ~(01+07+02+0B+00+00+02+05) = ~0x1C */
    kt_reply_is_hex(&fx, "F9 F5 01 07 02 0B 00 00 02 05 E3");
}

/* §2 "read servo status, ID 1 F9 FF 01 03 02 01 F8" -> "F9 F5 01 05 02 01 00 05 F1".
 * The random byte is xorshift32's first output from the init seed: find a seed
 * whose first output byte is 5, then the whole answer must match §2. */
static void test_s2_read_status_worked_frame(void **state)
{
    (void)state;
    uint32_t seed = 1;
    while ((uint8_t)kt_xorshift32(seed) != 5u) {
        seed++;
    }
    kt_init_seed(&fx, kt_product_pot(), 1, seed);
    kt_send_hex(&fx, "F9 FF 01 03 02 01 F8");
    kt_reply_is_hex(&fx, "F9 F5 01 05 02 01 00 05 F1");
    /* The next read draws the next number of the same sequence. */
    kt_send_hex(&fx, "F9 FF 01 03 02 01 F8");
    const uint8_t want[2] = {0x00, (uint8_t)kt_xorshift32(kt_xorshift32(seed))};
    kt_reply_is_read(&fx, 1, 0x01, want, 2);
}

/* §2 "restart ID 1 F9 FF 01 07 03 02 E1 E2 E3 E4 68": restart, no answer. */
static void test_s2_restart_worked_frame(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    kt_write_u8(&fx, 1, 0x11, 0x0A); /* response level 1: even then no answer */
    kt_send_hex(&fx, "F9 FF 01 07 03 02 E1 E2 E3 E4 68");
    kt_no_reply(&fx);
    assert_int_equal(fx.fake.restarts, 1);
}

/* §2 "write 0x65: 90.0°, 1000 ms, ID 1 F9 FF 01 07 03 65 84 03 E8 03 1D". */
static void test_s2_write_move_time_worked_frame(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    kt_send_hex(&fx, "F9 FF 01 07 03 65 84 03 E8 03 1D");
    kt_no_reply(&fx); /* response level 0 (0x11 default 0x02) */
    assert_int_equal(fx.fake.n_requests, 1);
    assert_int_equal(fx.fake.requests[0].kind, KM_REQ_MOVE);
    assert_int_equal(fx.fake.requests[0].u.move.kind, KM_MOVE_TIME);
    assert_int_equal(fx.fake.requests[0].u.move.target, 900);
    assert_int_equal(fx.fake.requests[0].u.move.time_or_speed, 1000);
    assert_int_equal(km_servo_status(&fx.s), 0);
}

/* The same frame with the torque switch off (0): refused, bit 6, no request. */
static void test_s2_write_move_time_worked_frame_torque_off(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    kt_write_u8(&fx, 1, 0x64, 0);
    const unsigned before = fx.fake.n_requests;
    kt_send_hex(&fx, "F9 FF 01 07 03 65 84 03 E8 03 1D");
    assert_int_equal(fx.fake.n_requests, before);
    assert_int_equal(km_servo_status(&fx.s) & KM_ST_FAILED, KM_ST_FAILED);
}

/* Servos 0..12 on one bus. */
#define NSERVO 13
static kt_fx_t bus[NSERVO];

static void bus_init(void)
{
    for (uint8_t i = 0; i < NSERVO; i++) {
        kt_init(&bus[i], kt_product_pot(), i);
    }
}

static void bus_send_hex(const char *hex)
{
    for (uint8_t i = 0; i < NSERVO; i++) {
        kt_send_hex(&bus[i], hex);
        kt_no_reply(&bus[i]);
    }
}

/* §2 "multi-ID write torque on 1,2,3 F9 FF FE 0A 83 64 01 01 02 02 02 03 02 03" */
static void test_s2_multi_id_torque_worked_frame(void **state)
{
    (void)state;
    bus_init();
    bus_send_hex("F9 FF FE 0A 83 64 01 01 02 02 02 03 02 03");
    for (uint8_t i = 0; i < NSERVO; i++) {
        if (i >= 1 && i <= 3) {
            assert_int_equal(bus[i].fake.n_requests, 1);
            assert_int_equal(bus[i].fake.requests[0].kind, KM_REQ_TORQUE);
            assert_int_equal(bus[i].fake.requests[0].u.torque, 2);
            assert_int_equal(km_servo_reg(&bus[i].s, KM_REG_TORQUE_SWITCH), 2);
        } else {
            assert_int_equal(bus[i].fake.n_requests, 0);
            assert_int_equal(km_servo_reg(&bus[i].s, KM_REG_TORQUE_SWITCH), 3);
        }
        assert_int_equal(km_servo_status(&bus[i].s), 0);
    }
}

static void check_moves_579(uint16_t param)
{
    for (uint8_t i = 0; i < NSERVO; i++) {
        int16_t target;
        if (i == 5) {
            target = 0;
        } else if (i == 7) {
            target = 90; /* 5A 00 = 9.0° */
        } else if (i == 9) {
            target = -90; /* A6 FF = -9.0° */
        } else {
            assert_int_equal(bus[i].fake.n_requests, 0);
            continue;
        }
        assert_int_equal(bus[i].fake.n_requests, 1);
        assert_int_equal(bus[i].fake.requests[0].kind, KM_REQ_MOVE);
        assert_int_equal(bus[i].fake.requests[0].u.move.kind, KM_MOVE_TIME);
        assert_int_equal(bus[i].fake.requests[0].u.move.target, target);
        assert_int_equal(bus[i].fake.requests[0].u.move.time_or_speed, param);
    }
}

/* §2 "multi-ID 0x65 to 5,7,9 F9 FF FE 13 83 65 04 05 00 00 E8 03 07 5A 00 E8 03 09 A6 FF E8 03 2D" */
static void test_s2_multi_id_move_worked_frame(void **state)
{
    (void)state;
    bus_init();
    bus_send_hex("F9 FF FE 13 83 65 04 05 00 00 E8 03 07 5A 00 E8 03 09 A6 FF E8 03 2D");
    check_moves_579(1000);
}

/* §2 "same, time omitted F9 FF FE 0D 83 65 02 05 00 00 07 5A 00 09 A6 FF F6":
 * time omitted = fastest (param 0). */
static void test_s2_multi_id_move_time_omitted_worked_frame(void **state)
{
    (void)state;
    bus_init();
    bus_send_hex("F9 FF FE 0D 83 65 02 05 00 00 07 5A 00 09 A6 FF F6");
    check_moves_579(0);
}

/* §2 "sync write torque on, ID 1/2/3 F9 FF 01 04 04 64 02 90 | ...02... 8F |
 * ...03... 8E" then "sync write execute (broadcast) F9 FF FE 02 84 7B". */
static void test_s2_sync_write_torque_worked_frames(void **state)
{
    (void)state;
    bus_init();
    bus_send_hex("F9 FF 01 04 04 64 02 90");
    bus_send_hex("F9 FF 02 04 04 64 02 8F");
    bus_send_hex("F9 FF 03 04 04 64 02 8E");
    for (uint8_t i = 0; i < NSERVO; i++) {
        assert_int_equal(bus[i].fake.n_requests, 0); /* buffered only */
        assert_int_equal(km_servo_reg(&bus[i].s, KM_REG_TORQUE_SWITCH), 3);
    }
    bus_send_hex("F9 FF FE 02 84 7B");
    for (uint8_t i = 0; i < NSERVO; i++) {
        if (i >= 1 && i <= 3) {
            assert_int_equal(bus[i].fake.n_requests, 1);
            assert_int_equal(bus[i].fake.requests[0].kind, KM_REQ_TORQUE);
            assert_int_equal(bus[i].fake.requests[0].u.torque, 2);
            assert_int_equal(km_servo_reg(&bus[i].s, KM_REG_TORQUE_SWITCH), 2);
        } else {
            assert_int_equal(bus[i].fake.n_requests, 0);
        }
    }
    /* The buffer is one-shot: a second execute does nothing. */
    bus_send_hex("F9 FF FE 02 84 7B");
    for (uint8_t i = 1; i <= 3; i++) {
        assert_int_equal(bus[i].fake.n_requests, 1);
    }
}

/* §2 "sync write 0x65 to 5 / 7 / 9" then execute. */
static void test_s2_sync_write_move_worked_frames(void **state)
{
    (void)state;
    bus_init();
    bus_send_hex("F9 FF 05 07 04 65 00 00 E8 03 9F");
    bus_send_hex("F9 FF 07 07 04 65 5A 00 E8 03 43");
    bus_send_hex("F9 FF 09 07 04 65 A6 FF E8 03 F6");
    for (uint8_t i = 0; i < NSERVO; i++) {
        assert_int_equal(bus[i].fake.n_requests, 0);
    }
    bus_send_hex("F9 FF FE 02 84 7B");
    check_moves_579(1000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s2_ping_worked_frame),
        cmocka_unit_test(test_s2_read_protocol_version_worked_frame),
        cmocka_unit_test(test_s2_read_status_worked_frame),
        cmocka_unit_test(test_s2_restart_worked_frame),
        cmocka_unit_test(test_s2_write_move_time_worked_frame),
        cmocka_unit_test(test_s2_write_move_time_worked_frame_torque_off),
        cmocka_unit_test(test_s2_multi_id_torque_worked_frame),
        cmocka_unit_test(test_s2_multi_id_move_worked_frame),
        cmocka_unit_test(test_s2_multi_id_move_time_omitted_worked_frame),
        cmocka_unit_test(test_s2_sync_write_torque_worked_frames),
        cmocka_unit_test(test_s2_sync_write_move_worked_frames),
    };
    return cmocka_run_group_tests_name("dispatch_frames", tests, NULL, NULL);
}
