/* SPDX-License-Identifier: Apache-2.0 */
/* The dispatcher's side of the servo <-> control seam (include/km/,
 * docs/architecture.md "Seams"):
 *  - km_servo_control_params() decodes the control registers into
 *    engineering units (0x11 bits, offsets, limits, 0x3C..0x3F fields,
 *    0x5A..0x5D, 0x64, the variant, the product's gains);
 *  - km_servo_params_gen() changes with every applied register change and
 *    only then;
 *  - a request control refuses is status bit 6 and changes nothing (0x64
 *    stays 3 when the rotation command that would turn it on is refused);
 *  - 0x64 shows control's torque switch when control set it by itself
 *    (live.torque_forced: 5 while a protection acts, what it returns to
 *    after), and keeps the master's value otherwise. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_test_support.h"

static kt_fx_t fx;

static void test_params_decoded_in_engineering_units(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    km_control_params_t p;
    km_servo_control_params(&fx.s, &p);
    /* product defaults */
    assert_int_equal(p.variant, KM_VARIANT_POTENTIOMETER);
    assert_false(p.reverse);
    assert_true(p.idle_brake); /* 0x11 = 0x02 */
    assert_false(p.power_on_brake);
    assert_int_equal(p.zero_offset1, 37);
    assert_int_equal(p.zero_offset2, 0);
    assert_int_equal(p.max_torque, 1000);
    assert_int_equal(p.max_current_ma, 2000);
    assert_int_equal(p.max_speed_dps, 600);
    assert_int_equal(p.angle_min, -1350);
    assert_int_equal(p.angle_max, 1350);
    assert_int_equal(p.travel_min, -1350);
    assert_int_equal(p.travel_max, 1350);
    assert_int_equal(p.prot_enable, 0x0F);
    assert_int_equal(p.prot_release, 0x00);
    assert_int_equal(p.prot_state, 0x54);
    assert_int_equal(p.voltage_high_v, 14);
    assert_int_equal(p.voltage_low_v, 6);
    assert_int_equal(p.temp_trip_c, 60);
    assert_int_equal(p.temp_hysteresis_c, 5);
    assert_int_equal(p.current_trip_ma, 1800);
    assert_int_equal(p.current_time_100ms, 20);
    assert_int_equal(p.stall_pwm, 600);
    assert_int_equal(p.stall_time_100ms, 20);
    assert_int_equal(p.control_mode, 0);
    assert_int_equal(p.torque_limit, 1000);
    assert_int_equal(p.current_limit_ma, 2000);
    assert_int_equal(p.speed_limit_dps, 600);
    assert_int_equal(p.torque_switch, 3);
    const km_control_gains_t g = KM_CONTROL_GAINS_DEFAULT; /* the test product sets none */
    assert_int_equal(p.gains.kp_q8, g.kp_q8);
    assert_int_equal(p.gains.kd_q8, g.kd_q8);
    assert_int_equal(p.gains.ki_q8, g.ki_q8);
    assert_int_equal(p.gains.i_max_pwm, g.i_max_pwm);
    assert_int_equal(p.gains.kv_q8, g.kv_q8);
    assert_int_equal(p.gains.friction_pwm, g.friction_pwm);
    assert_int_equal(p.gains.tau_ms, g.tau_ms);
    assert_int_equal(p.gains.accel_dps2, g.accel_dps2);
    assert_int_equal(p.gains.fastest_dps, g.fastest_dps);
    assert_int_equal(p.gains.arrive_ddeg, g.arrive_ddeg);
    assert_int_equal(p.gains.settle_ms, g.settle_ms);

    /* written values come through decoded */
    kt_write_u8(&fx, 1, 0x11, 0x0D);     /* response level, direction, power-on brake */
    const uint8_t zo2[2] = {0x9C, 0xFF}; /* -100 */
    kt_write(&fx, 1, 0x17, zo2, 2);
    kt_write_u16(&fx, 1, 0x5B, 400);
    kt_write_u16(&fx, 1, 0x5D, 90);
    const uint8_t stall[3] = {0x2C, 0x01, 0x0A}; /* 300 PWM, 1.0 s */
    kt_write(&fx, 1, 0x3F, stall, 3);
    kt_write_u8(&fx, 1, 0x5A, 1);
    kt_write_u8(&fx, 1, 0x64, 2);
    km_servo_control_params(&fx.s, &p);
    assert_true(p.reverse);
    assert_false(p.idle_brake);
    assert_true(p.power_on_brake);
    assert_int_equal(p.zero_offset2, -100);
    assert_int_equal(p.torque_limit, 400);
    assert_int_equal(p.speed_limit_dps, 90);
    assert_int_equal(p.stall_pwm, 300);
    assert_int_equal(p.stall_time_100ms, 10);
    assert_int_equal(p.control_mode, 1);
    assert_int_equal(p.torque_switch, 2);

    kt_init(&fx, kt_product_enc(), 1);
    km_servo_control_params(&fx.s, &p);
    assert_int_equal(p.variant, KM_VARIANT_ENCODER);
    assert_int_equal(p.angle_min, 0);
    assert_int_equal(p.zero_offset1, -12);
}

/* The change counter moves on every applied change (a persisted write, a
 * runtime write, 0x64, 3 -> 2 by a rotation command) and not on reads,
 * pings, refused writes or rotation commands that change no register. */
static void test_params_gen_counts_applied_changes(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    uint32_t g = km_servo_params_gen(&fx.s);
    kt_read(&fx, 1, 0x46);
    kt_ping(&fx, 1);
    assert_int_equal(km_servo_params_gen(&fx.s), g);
    kt_write_u16(&fx, 1, 0x5B, 2000); /* out of range: refused */
    assert_int_equal(km_servo_params_gen(&fx.s), g);
    kt_write_u16(&fx, 1, 0x5B, 500);
    assert_true(km_servo_params_gen(&fx.s) != g);
    g = km_servo_params_gen(&fx.s);
    kt_write_u16(&fx, 1, 0x13, 800); /* persisted: after its commit */
    assert_true(km_servo_params_gen(&fx.s) != g);
    g = km_servo_params_gen(&fx.s);
    const uint8_t move[4] = {0x84, 0x03, 0xE8, 0x03};
    kt_write(&fx, 1, 0x65, move, 4); /* 0x64 3 -> 2 */
    assert_true(km_servo_params_gen(&fx.s) != g);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_SWITCH), 2);
    g = km_servo_params_gen(&fx.s);
    kt_write(&fx, 1, 0x65, move, 4); /* already on: no register changes */
    assert_int_equal(km_servo_params_gen(&fx.s), g);
    fx.fake.fail_next_commit = true;
    kt_write_u16(&fx, 1, 0x13, 700); /* the store failed: nothing applied */
    assert_int_equal(km_servo_params_gen(&fx.s), g);
}

/* A request control refuses: bit 6, and the register stays. */
static void test_refused_request_is_bit6_and_changes_nothing(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    kt_ping_is(&fx, 1, 0x00);
    fx.fake.refuse_requests = true;
    const uint8_t move[4] = {0x84, 0x03, 0xE8, 0x03};
    kt_write(&fx, 1, 0x65, move, 4);
    assert_int_equal(fx.fake.n_requests, 1);                        /* it was asked */
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_SWITCH), 3); /* not turned on */
    kt_ping_is(&fx, 1, 0x40);
    kt_write_u8(&fx, 1, 0x64, 1);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_SWITCH), 3);
    kt_ping_is(&fx, 1, 0x40);
    const uint8_t pwm[2] = {0xF4, 0x01};
    kt_write(&fx, 1, 0x6E, pwm, 2);
    kt_ping_is(&fx, 1, 0x40);
    fx.fake.refuse_requests = false;
    kt_write_u8(&fx, 1, 0x64, 1);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_SWITCH), 1);
    kt_ping_is(&fx, 1, 0x00);
}

/* A protection acting (control forces its torque switch, 5) makes 0x64
 * read 5; at the release control forces what 0x64 returns to; a tick that
 * forces nothing leaves the master's value; a write of 0..3 afterwards is a
 * torque request as usual. */
static void test_protecting_reads_5(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    km_live_t live = {0};
    live.protecting = true;
    live.torque_forced = true;
    live.torque_switch = KM_TORQUE_PROTECTED;
    km_servo_set_live(&fx.s, &live);
    const uint8_t five[1] = {5};
    kt_read(&fx, 1, 0x64);
    kt_reply_is_read(&fx, 1, 0x64, five, 1);
    live.protecting = false; /* the release: back to armed */
    live.torque_switch = KM_TORQUE_ARMED;
    km_servo_set_live(&fx.s, &live);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_SWITCH), 3);
    kt_write_u8(&fx, 1, 0x64, 0);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_SWITCH), 0);
    live.torque_forced = false; /* an ordinary tick: 0x64 is the master's */
    live.torque_switch = KM_TORQUE_ON;
    km_servo_set_live(&fx.s, &live);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_SWITCH), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_params_decoded_in_engineering_units),
        cmocka_unit_test(test_params_gen_counts_applied_changes),
        cmocka_unit_test(test_refused_request_is_bit6_and_changes_nothing),
        cmocka_unit_test(test_protecting_reads_5),
    };
    return cmocka_run_group_tests_name("control seam", tests, NULL, NULL);
}
