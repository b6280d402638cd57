/* SPDX-License-Identifier: Apache-2.0 */
/* Motor mode on the simulated plant (docs/protocol.md §5.4 0x6E..0x70, 0x5A,
 * 0x4D, status bit 7; §6 variants): control stepped against km_plant_step
 * at the 1 kHz tick (tests/support/km_plant_rig.h), default plant (20
 * kg.cm class, 7.4 V) and default gains.
 *
 * The plant is configured as an encoder product here (no pot travel, no
 * end stops, position from the multi-turn reading): a pot servo's end
 * stops at +-150 deg would stop a constant-PWM run within a second. So
 * multi-turn runs (0x70 turns) are shown on the plant's turn count; what
 * the plant cannot show is a real encoder's wrap/restart behaviour.
 *
 * Figures the tests hold (the bounds are what is asserted):
 *  - constant PWM: the speed over 100 ms windows is steady within +-2 %
 *    after 300 ms; the sign follows the PWM's; 0 stops the shaft within
 *    150 ms (brake, the idle output of 0x11 bit 1);
 *  - 0x5B: |bridge PWM| never above it;
 *  - 0x70 run for 0.5 s: bit 7 clears at 500 +-1 ms, 0x4D reads 500 +-1;
 *    then brake (shaft at rest within 150 ms) or free (coasts) as asked;
 *  - 0x6F 180 deg/s: the mean speed over every 100 ms window from 400 ms
 *    to 2 s is within +-3 % of it (+-5.4 deg/s); 0x5D cuts the set-point;
 *  - 0x70 angle 90 deg at 180 deg/s: the shaft stops (brake) within 6 deg
 *    past it (4.5 seen); 2.5 turns reversed at PWM 800 (~290 deg/s):
 *    within 10 deg past -900 deg (7.7 seen): the braking distance of the
 *    plant at that speed, the run ends on the tick the distance is met.
 *  - auto hand-over: a relative 0x67 +10 deg after a motor run lands
 *    within 0.5 deg of where the shaft was at the command + 10 deg. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_plant_rig.h"
#include "km_test_support.h"

static kr_rig_t r;
static kt_fx_t fx;

/* Encoder product on a free multi-turn plant, at rest at 0. */
static void rig_encoder(void)
{
    static km_plant_config_t cfg;
    kr_init_encoder_at(&r, &cfg, &km_plant_default_config, 0);
}

/* 0x6E (KM_RUN_PWM) or 0x6F (KM_RUN_SPEED) as the dispatcher decodes it. */
static bool motor_signed(km_run_mode_t mode, int16_t v)
{
    return kr_motor_signed(&r, mode, v);
}

/* A 0x70 run as the dispatcher decodes it. */
static bool motor_run(km_run_mode_t mode, bool reverse, uint16_t value, km_run_until_t until, uint16_t amount,
                      km_run_after_t after)
{
    return kr_run_motor(&r, mode, reverse, value, until, amount, after);
}

/* Mean speed over `ms` ticks from the turn count, deg/s x 10 (master's
 * frame when not reversed). */
static int32_t mean_ddps(uint32_t ms)
{
    const int32_t a = km_plant_turns_ddeg(&r.plant);
    kr_run(&r, ms);
    return (km_plant_turns_ddeg(&r.plant) - a) * 1000 / (int32_t)ms;
}

static int32_t iabs(int32_t v)
{
    return v < 0 ? -v : v;
}

/* §5.4 0x6E: constant PWM reaches a steady speed; the sign follows. */
static void test_s5_4_0x6E_steady_speed_and_sign(void **state)
{
    (void)state;
    rig_encoder();
    assert_true(motor_signed(KM_RUN_PWM, 500));
    kr_run(&r, 300);
    assert_true(r.live.running);
    assert_int_equal(r.bridge.mode, KM_BRIDGE_PWM);
    assert_int_equal(r.bridge.pwm, 500);
    const int32_t v1 = mean_ddps(100);
    const int32_t v2 = mean_ddps(100);
    const int32_t v3 = mean_ddps(100);
    print_message("0x6E 500: %d, %d, %d x0.1 deg/s\n", (int)v1, (int)v2, (int)v3);
    assert_true(v1 > 500); /* > 50 deg/s forward */
    assert_true(iabs(v2 - v1) * 50 <= v1 && iabs(v3 - v1) * 50 <= v1);

    assert_true(motor_signed(KM_RUN_PWM, -500));
    kr_run(&r, 400);
    const int32_t vn = mean_ddps(100);
    assert_true(vn < 0);
    assert_true(iabs(iabs(vn) - v1) * 50 <= v1); /* same speed, other way */
}

/* §5.4 0x6E 0 = stop: bit 7 clears, the idle output (brake), shaft at rest. */
static void test_s5_4_0x6E_zero_stops(void **state)
{
    (void)state;
    rig_encoder();
    assert_true(motor_signed(KM_RUN_PWM, 800));
    kr_run(&r, 400);
    assert_true(km_plant_speed_mdps(&r.plant) > 50000);
    assert_true(motor_signed(KM_RUN_PWM, 0));
    kr_run(&r, 1);
    assert_false(r.live.running);
    assert_int_equal(r.bridge.mode, KM_BRIDGE_BRAKE);
    kr_run(&r, 150);
    assert_true(iabs(km_plant_speed_mdps(&r.plant)) < 1000);
    assert_int_equal(r.live.pwm, 0);
}

/* §5.4 0x5B: the torque limit bounds the motor's PWM. */
static void test_s5_4_0x5B_limits_motor_pwm(void **state)
{
    (void)state;
    rig_encoder();
    r.params.torque_limit = 300;
    assert_true(motor_signed(KM_RUN_PWM, 1000));
    for (int i = 0; i < 500; i++) {
        kr_tick(&r);
        assert_true(iabs(r.bridge.pwm) <= 300);
    }
    assert_int_equal(r.live.pwm, 300);
    /* and the speed loop is bounded the same way */
    assert_true(motor_signed(KM_RUN_SPEED, 300));
    for (int i = 0; i < 500; i++) {
        kr_tick(&r);
        assert_true(iabs(r.bridge.pwm) <= 300);
    }
}

/* §5.4 0x70 time run: stops at the time, then brakes or frees as bit 1
 * says; bit 7 and 0x4D follow the run. Works on a pot product too (PWM). */
static void run_for_time(bool brake)
{
    kr_init(&r); /* potentiometer product: time + PWM is allowed */
    km_plant_set_position_ddeg(&r.plant, -1200);
    kr_run(&r, 5);
    /* 0.5 s at PWM 600, then braked or free */
    assert_true(motor_run(KM_RUN_PWM, false, 600, KM_UNTIL_TIME, 5, brake ? KM_AFTER_BRAKE : KM_AFTER_FREE));
    int32_t end = -1;
    for (int32_t i = 1; i <= 700; i++) {
        kr_tick(&r);
        if (end < 0 && !r.live.running) {
            end = i;
        }
    }
    print_message("0x70 0.5 s (%s): ended at %d ms, 0x4D %u\n", brake ? "brake" : "free", (int)end,
                  (unsigned)r.live.rotation_ms);
    assert_true(end >= 499 && end <= 501);
    assert_true(r.live.rotation_ms >= 499 && r.live.rotation_ms <= 501);
    assert_int_equal(r.bridge.mode, brake ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE);
}

static void test_s5_4_0x70_time_then_brake(void **state)
{
    (void)state;
    run_for_time(true);
    assert_true(iabs(km_plant_speed_mdps(&r.plant)) < 1000); /* braked to rest in 200 ms */
}

static void test_s5_4_0x70_time_then_free(void **state)
{
    (void)state;
    run_for_time(false);
    assert_int_equal(r.in.bridge, KM_PLANT_COAST);
}

/* §5.4 0x70 bit 7: stop now, with bit 1's output. */
static void test_s5_4_0x70_stop_now(void **state)
{
    (void)state;
    rig_encoder();
    assert_true(motor_run(KM_RUN_PWM, false, 700, KM_UNTIL_NONE, 0, KM_AFTER_FREE)); /* run on, PWM 700 */
    kr_run(&r, 200);
    assert_true(r.live.running);
    assert_true(motor_run(KM_RUN_STOP, false, 0, KM_UNTIL_NONE, 0, KM_AFTER_BRAKE)); /* stop, brake */
    kr_run(&r, 1);
    assert_false(r.live.running);
    assert_int_equal(r.bridge.mode, KM_BRIDGE_BRAKE);
}

/* §5.4 0x6F (encoder): the speed loop holds the speed within +-3 %; the
 * sign follows; 0x5D cuts it. */
static void test_s5_4_0x6F_holds_speed(void **state)
{
    (void)state;
    rig_encoder();
    assert_true(motor_signed(KM_RUN_SPEED, 180));
    kr_run(&r, 400);
    int32_t lo = INT32_MAX, hi = INT32_MIN;
    for (int i = 0; i < 16; i++) {
        const int32_t v = mean_ddps(100);
        lo = v < lo ? v : lo;
        hi = v > hi ? v : hi;
    }
    print_message("0x6F 180 deg/s: %d..%d x0.1 deg/s over 100 ms windows\n", (int)lo, (int)hi);
    assert_true(lo >= 1800 - 54 && hi <= 1800 + 54);
    assert_true(r.live.running);

    assert_true(motor_signed(KM_RUN_SPEED, -90));
    kr_run(&r, 500);
    const int32_t vn = mean_ddps(200);
    assert_true(vn <= -900 + 27 && vn >= -900 - 27);

    r.params.speed_limit_dps = 60; /* 0x5D */
    assert_true(motor_signed(KM_RUN_SPEED, 300));
    kr_run(&r, 500);
    const int32_t vl = mean_ddps(200);
    assert_true(vl >= 600 - 18 && vl <= 600 + 18);

    assert_true(motor_signed(KM_RUN_SPEED, 0));
    kr_run(&r, 200);
    assert_false(r.live.running);
    assert_true(iabs(km_plant_speed_mdps(&r.plant)) < 1000);
}

/* §5.4 0x70 angle and turns (encoder): the run ends at the distance;
 * bit 0 reverses. */
static void test_s5_4_0x70_angle_and_turns(void **state)
{
    (void)state;
    rig_encoder();
    assert_true(motor_run(KM_RUN_SPEED, false, 180, KM_UNTIL_ANGLE, 90,
                          KM_AFTER_BRAKE)); /* 90 deg at 180 deg/s, brake */
    kr_run(&r, 1500);
    int32_t pos = km_plant_turns_ddeg(&r.plant);
    print_message("0x70 90 deg: stopped at %d x0.1 deg\n", (int)pos);
    assert_false(r.live.running);
    assert_true(pos >= 900 && pos <= 900 + 60);

    rig_encoder();
    assert_true(motor_run(KM_RUN_PWM, true, 800, KM_UNTIL_TURNS, 25,
                          KM_AFTER_BRAKE)); /* 2.5 turns reverse at PWM 800, brake */
    kr_run(&r, 6000);
    pos = km_plant_turns_ddeg(&r.plant);
    print_message("0x70 -2.5 turns: stopped at %d x0.1 deg\n", (int)pos);
    assert_false(r.live.running);
    assert_true(pos <= -9000 && pos >= -9000 - 100);
}

/* §5.1 0x11 bit 2 applies to motor mode as to servo mode: the bridge turns
 * the sensor's way, positive PWM is positive in the master's frame. */
static void test_s5_4_motor_direction_bit(void **state)
{
    (void)state;
    rig_encoder();
    r.params.reverse = true;
    const int32_t p0 = kr_pos(&r);
    assert_true(motor_signed(KM_RUN_PWM, 400));
    kr_run(&r, 300);
    assert_int_equal(r.bridge.pwm, -400);
    assert_true(kr_pos(&r) > p0 + 100);
    assert_true(km_plant_speed_mdps(&r.plant) < 0);
}

/* §5.4 0x5A = 0 (auto): a motor command ends a servo hold, a servo command
 * takes the shaft back from where the motor left it; a torque switch write
 * ends the motor; 0x5A = 1 stops a running motor. */
static void test_s5_4_0x5A_auto_hand_over(void **state)
{
    (void)state;
    rig_encoder();
    assert_true(kr_torque(&r, 2));
    kr_run(&r, 100);
    assert_int_equal(r.bridge.mode, KM_BRIDGE_PWM);
    assert_true(motor_signed(KM_RUN_PWM, 400));
    kr_run(&r, 300);
    assert_true(r.live.running);
    assert_int_equal(r.bridge.pwm, 400);
    assert_int_equal(r.live.deviation, 0);
    /* servo command: relative +10 deg from where the shaft is */
    const int32_t here = kr_pos(&r);
    assert_true(kr_move_rel(&r, KM_MOVE_TIME, 100, 0));
    kr_run(&r, 1500);
    print_message("servo after motor: from %d to %d (want %d)\n", (int)here, (int)kr_pos(&r),
                  (int)(here + 100));
    assert_false(r.live.running);
    /* the shaft was still turning when the move began: it lands on the
     * target counted from the position at the command */
    assert_true(iabs(kr_pos(&r) - (here + 100)) <= 5);

    /* torque switch 0 ends the motor: free */
    assert_true(motor_signed(KM_RUN_PWM, 300));
    kr_run(&r, 50);
    assert_true(kr_torque(&r, 0));
    kr_run(&r, 1);
    assert_false(r.live.running);
    assert_int_equal(r.bridge.mode, KM_BRIDGE_FREE);

    /* 0x5A = 1 written while the motor runs stops it (idle output) */
    assert_true(motor_signed(KM_RUN_PWM, 300));
    kr_run(&r, 50);
    r.params.control_mode = 1;
    kr_run(&r, 1);
    assert_false(r.live.running);
    assert_int_equal(r.bridge.mode, KM_BRIDGE_BRAKE);
}

/* §5.4 0x5A over the dispatcher (one place for the rule): 1 refuses motor
 * commands, 2 refuses servo commands and is refused itself while a servo
 * move runs with the torque on. */
static void test_s5_4_0x5A_rule_in_dispatcher(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_enc(), 1);
    kt_write_u8(&fx, 1, 0x5A, 1);
    const unsigned n = fx.fake.n_requests;
    const uint8_t pwm[2] = {0xF4, 0x01};
    kt_write(&fx, 1, 0x6E, pwm, 2);
    kt_ping_is(&fx, 1, 0x40);
    assert_int_equal(fx.fake.n_requests, n);
    kt_write_u8(&fx, 1, 0x5A, 0);
    kt_write(&fx, 1, 0x6E, pwm, 2);
    kt_ping_is(&fx, 1, 0x00);
    assert_int_equal(fx.fake.n_requests, n + 1);
}

/* §6: a potentiometer product refuses 0x6F and 0x70 angle/turns/speed with
 * status bit 6 and nothing reaches control; time + PWM is fine. */
static void test_s6_pot_refuses_encoder_motor_commands(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    const uint8_t spd[2] = {0x64, 0x00};
    const uint8_t angle[5] = {0x20, 0x5A, 0x00, 0x64, 0x00};
    const uint8_t turns[5] = {0x30, 0x0A, 0x00, 0x64, 0x00};
    const uint8_t speed[5] = {0x04, 0x00, 0x00, 0x64, 0x00};
    const uint8_t timed[5] = {0x10, 0x05, 0x00, 0x64, 0x00};
    const unsigned n = fx.fake.n_requests;
    kt_write(&fx, 1, 0x6F, spd, 2);
    kt_ping_is(&fx, 1, 0x40);
    kt_write(&fx, 1, 0x70, angle, 5);
    kt_ping_is(&fx, 1, 0x40);
    kt_write(&fx, 1, 0x70, turns, 5);
    kt_ping_is(&fx, 1, 0x40);
    kt_write(&fx, 1, 0x70, speed, 5);
    kt_ping_is(&fx, 1, 0x40);
    assert_int_equal(fx.fake.n_requests, n);
    kt_write(&fx, 1, 0x70, timed, 5);
    kt_ping_is(&fx, 1, 0x00);
    assert_int_equal(fx.fake.n_requests, n + 1);
    assert_int_equal(fx.fake.requests[n].kind, KM_REQ_MOTOR);
    assert_int_equal(fx.fake.requests[n].u.run.mode, KM_RUN_PWM);
    assert_int_equal(fx.fake.requests[n].u.run.until, KM_UNTIL_TIME);
    assert_int_equal(fx.fake.requests[n].u.run.amount, 5);
    assert_int_equal(fx.fake.requests[n].u.run.value, 100);
}

/* Control stays defined for any value that reaches it (the dispatcher
 * validates first; checked under UBSan too): every decoded run (mode,
 * direction, bound, output after) with extreme amounts and values, extreme
 * 0x6E/0x6F values, extreme gains; the bridge PWM stays within +-1000. */
static void test_s5_4_motor_any_value_defined(void **state)
{
    (void)state;
    rig_encoder();
    r.params.gains.kv_q8 = UINT16_MAX;
    r.params.gains.kd_q8 = UINT16_MAX;
    r.params.gains.i_max_pwm = UINT16_MAX;
    r.params.gains.friction_pwm = UINT16_MAX;
    r.params.speed_limit_dps = UINT16_MAX;
    const int16_t v16[] = {INT16_MIN, -1001, -1, 0, 1, 1000, INT16_MAX};
    for (unsigned i = 0; i < sizeof v16 / sizeof v16[0]; i++) {
        assert_true(motor_signed(KM_RUN_PWM, v16[i]));
        kr_run(&r, 3);
        assert_true(iabs(r.bridge.pwm) <= 1000);
        assert_true(motor_signed(KM_RUN_SPEED, v16[i]));
        kr_run(&r, 3);
        assert_true(iabs(r.bridge.pwm) <= 1000);
    }
    /* every run the decoded 0x70 can ask for, at the extreme values */
    const uint16_t p[] = {0, 1, UINT16_MAX};
    for (unsigned c = 0; c < 3u * 2u * 4u * 3u; c++) {
        const km_run_mode_t mode = (km_run_mode_t)(c % 3u);
        const bool reverse = (c / 3u) % 2u != 0u;
        const km_run_until_t until = (km_run_until_t)((c / 6u) % 4u);
        const km_run_after_t after = (km_run_after_t)(c / 24u);
        for (unsigned a = 0; a < 3u; a++) {
            for (unsigned b = 0; b < 3u; b++) {
                assert_true(motor_run(mode, reverse, p[b], until, p[a], after));
                kr_run(&r, 2);
                assert_true(iabs(r.bridge.pwm) <= 1000);
            }
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s5_4_0x6E_steady_speed_and_sign),
        cmocka_unit_test(test_s5_4_0x6E_zero_stops),
        cmocka_unit_test(test_s5_4_0x5B_limits_motor_pwm),
        cmocka_unit_test(test_s5_4_0x70_time_then_brake),
        cmocka_unit_test(test_s5_4_0x70_time_then_free),
        cmocka_unit_test(test_s5_4_0x70_stop_now),
        cmocka_unit_test(test_s5_4_0x6F_holds_speed),
        cmocka_unit_test(test_s5_4_0x70_angle_and_turns),
        cmocka_unit_test(test_s5_4_motor_direction_bit),
        cmocka_unit_test(test_s5_4_0x5A_auto_hand_over),
        cmocka_unit_test(test_s5_4_motor_any_value_defined),
        cmocka_unit_test(test_s5_4_0x5A_rule_in_dispatcher),
        cmocka_unit_test(test_s6_pot_refuses_encoder_motor_commands),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
