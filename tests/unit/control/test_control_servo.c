/* SPDX-License-Identifier: Apache-2.0 */
/* Servo mode on the simulated plant (docs/protocol.md §5.4, §5.1, §5.3): control
 * stepped against km_plant_step at the 1 kHz tick with a one-tick PWM delay
 * (tests/support/km_plant_rig.h), default plant (20 kg.cm class, 7.4 V) and
 * default gains (include/km/km_product.h, docs/tuning.md).
 *
 * Figures the tests hold (the bounds are what is asserted):
 *  - arrival: the move ends (bit 7 clears) within the arrive band of
 *    +-0.5 deg; 1 s later the shaft is within +-0.2 deg of the target;
 *  - a move in time T ends within T + 40 ms (and not before T - 20 ms);
 *  - overshoot past the target <= 0.3 deg for every move in the table
 *    (time, speed and fastest moves, 0.2..120 deg, light load);
 *  - 0x68 streams at 50 Hz and 100 Hz: the shaft speed stays within +-5 %
 *    of the stream speed once under way (no stop-and-go). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_plant_rig.h"

#define ARRIVE_DDEG 5 /* the default gains' arrive band */
#define FINAL_DDEG 2  /* where it sits 1 s after arriving */
#define OVERSHOOT_DDEG 3

static kr_rig_t r;

typedef struct {
    int32_t max_pos, min_pos; /* reported position extremes */
    int32_t max_abs_pwm;      /* |bridge PWM| */
    int32_t max_abs_speed;    /* plant speed, m deg/s */
    int32_t end_ms;           /* tick bit 7 cleared, -1 = still running */
    bool running_seen;
} run_t;

/* Runs `ms` ticks; records extremes and when the running bit cleared. */
static run_t run_watch(uint32_t ms)
{
    run_t w = {INT32_MIN, INT32_MAX, 0, 0, -1, false};
    for (uint32_t i = 0; i < ms; i++) {
        kr_tick(&r);
        const int32_t pos = kr_pos(&r);
        w.max_pos = pos > w.max_pos ? pos : w.max_pos;
        w.min_pos = pos < w.min_pos ? pos : w.min_pos;
        const int32_t pwm = r.bridge.pwm < 0 ? -r.bridge.pwm : r.bridge.pwm;
        w.max_abs_pwm = pwm > w.max_abs_pwm ? pwm : w.max_abs_pwm;
        int32_t v = km_plant_speed_mdps(&r.plant);
        v = v < 0 ? -v : v;
        w.max_abs_speed = v > w.max_abs_speed ? v : w.max_abs_speed;
        if (r.live.running) {
            w.running_seen = true;
        } else if (w.end_ms < 0 && w.running_seen) {
            w.end_ms = (int32_t)i;
        }
    }
    return w;
}

static void on_at(int32_t pos)
{
    kr_init_at(&r, &km_plant_default_config, pos);
    assert_true(kr_torque(&r, 2));
    kr_run(&r, 5);
}

static void near(int32_t got, int32_t want, int32_t tol)
{
    if (got < want - tol || got > want + tol) {
        fail_msg("position %d, want %d +- %d", got, want, tol);
    }
}

/* §5.4 0x65: +45.0 deg in 500 ms: the move ends (bit 7 clears) within the
 * arrive band in about 500 ms, 0x4D stops there, the shaft holds. */
static void test_s5_4_move_time_45deg_500ms(void **state)
{
    (void)state;
    on_at(0);
    assert_true(kr_move(&r, KM_MOVE_TIME, 450, 500));
    kr_tick(&r);
    assert_true(r.live.running);
    assert_true(r.live.deviation < 0); /* position - target: behind */
    const run_t w = run_watch(1500);
    assert_true(w.end_ms >= 480 && w.end_ms <= 540);
    near(kr_pos(&r), 450, FINAL_DDEG);
    assert_true(w.max_pos <= 450 + OVERSHOOT_DDEG);
    assert_false(r.live.running);
    assert_true(r.live.rotation_ms >= 480 && r.live.rotation_ms <= 540);
    const uint32_t frozen = r.live.rotation_ms;
    kr_run(&r, 200);
    assert_int_equal(r.live.rotation_ms, frozen); /* stops counting when the motion ends */
    near(r.live.deviation, 0, FINAL_DDEG);
    assert_int_equal(r.ctl.servo.ts, 2);
}

/* Every command kind over a table of moves: end time, final position and
 * the overshoot bound. Time moves end within [T - 20, T + 40] ms; speed
 * moves no later than D / v + v / a + 60 ms. */
static void test_s5_4_move_table_overshoot_bound(void **state)
{
    (void)state;
    static const struct {
        km_move_kind_t kind;
        int32_t from, to;
        uint16_t param;
    } t[] = {
        {KM_MOVE_TIME, 0, 450, 500},     {KM_MOVE_TIME, 0, -900, 1000}, {KM_MOVE_TIME, 0, 20, 100},
        {KM_MOVE_TIME, -600, 600, 2000}, {KM_MOVE_TIME, 100, 102, 50},  {KM_MOVE_TIME, 0, 1200, 0},
        {KM_MOVE_SPEED, 0, 900, 90},     {KM_MOVE_SPEED, 0, -450, 300}, {KM_MOVE_SPEED, 300, -900, 0},
        {KM_MOVE_SPEED, 0, 5, 10},       {KM_MOVE_SPEED, 0, 1200, 0},
    };
    for (unsigned i = 0; i < sizeof t / sizeof t[0]; i++) {
        on_at(t[i].from);
        assert_true(kr_move(&r, t[i].kind, (int16_t)t[i].to, t[i].param));
        const run_t w = run_watch(4000);
        const int32_t d = t[i].to > t[i].from ? t[i].to - t[i].from : t[i].from - t[i].to;
        int32_t over = t[i].to > t[i].from ? w.max_pos - t[i].to : t[i].to - w.min_pos;
        if (over > OVERSHOOT_DDEG || w.end_ms < 0) {
            fail_msg("move %u: overshoot %d (0.1 deg), end %d ms", i, over, w.end_ms);
        }
        near(kr_pos(&r), t[i].to, FINAL_DDEG);
        print_message("move %2u: %s %5d -> %5d (%4u): ended %4d ms, overshoot %d x 0.1 deg, peak PWM %d\n", i,
                      t[i].kind == KM_MOVE_TIME ? "0x65" : "0x66", t[i].from, t[i].to, t[i].param, w.end_ms,
                      over > 0 ? over : 0, w.max_abs_pwm);
        if (t[i].kind == KM_MOVE_TIME && t[i].param != 0) {
            if (w.end_ms < t[i].param - 20 || w.end_ms > t[i].param + 40) {
                fail_msg("move %u: ended at %d ms, asked %u", i, w.end_ms, t[i].param);
            }
        } else {
            const int32_t v = t[i].param ? t[i].param : 360;          /* deg/s, 0 = 0x5D */
            const int32_t bound = d * 100 / v + v * 1000 / 4000 + 60; /* ms */
            if (w.end_ms > bound) {
                fail_msg("move %u: ended at %d ms, bound %d", i, w.end_ms, bound);
            }
        }
    }
}

/* 0x5B torque limit: |PWM| never above it, the move still arrives. */
static void test_s5_4_torque_limit_5b(void **state)
{
    (void)state;
    on_at(0);
    r.params.torque_limit = 300;
    assert_true(kr_move(&r, KM_MOVE_SPEED, 900, 0));
    const run_t w = run_watch(3000);
    assert_true(w.max_abs_pwm <= 300);
    assert_true(w.max_abs_pwm >= 250); /* it did use it */
    near(kr_pos(&r), 900, FINAL_DDEG);
    /* 0x67 low nibble 2: a move's own PWM cap below 0x5B */
    r.params.torque_limit = 1000;
    assert_true(kr_move_capped(&r, 0, 200));
    const run_t w2 = run_watch(4000);
    assert_true(w2.max_abs_pwm <= 200);
    near(kr_pos(&r), 0, FINAL_DDEG);
}

/* 0x5D speed limit: "fastest" runs at it, a faster speed is cut to it, and
 * a move in time that would need more takes longer. The set-point never
 * goes faster than 0x5D; the shaft's reported speed (0x47, 20 ms window)
 * stays within +5 % of it, its instantaneous speed within +15 % (the
 * loop catching up the start-up lag). */
static void speed_limited_move(km_move_kind_t kind, int16_t target, uint16_t param)
{
    assert_true(kr_move(&r, kind, target, param));
    int32_t max_sp = 0, max_47 = 0, max_plant = 0;
    for (unsigned i = 0; i < 3000; i++) {
        kr_tick(&r);
        const int32_t sp = r.ctl.servo.profile.vel < 0 ? -r.ctl.servo.profile.vel : r.ctl.servo.profile.vel;
        const int32_t s47 = r.live.speed < 0 ? -r.live.speed : r.live.speed;
        int32_t v = km_plant_speed_mdps(&r.plant);
        v = v < 0 ? -v : v;
        max_sp = sp > max_sp ? sp : max_sp;
        max_47 = s47 > max_47 ? s47 : max_47;
        max_plant = v > max_plant ? v : max_plant;
    }
    print_message(
        "0x5D = 90, request kind %d: set-point max %d u/s, 0x47 max %d deg/s, shaft max %d m deg/s\n", kind,
        max_sp, max_47, max_plant);
    assert_true(max_sp <= 90 * KM_PROFILE_UPS_PER_DPS);
    assert_true(max_47 <= 94);
    assert_true(max_plant <= 103500);
    near(kr_pos(&r), target, FINAL_DDEG);
}

static void test_s5_4_speed_limit_5d(void **state)
{
    (void)state;
    on_at(0);
    r.params.speed_limit_dps = 90;
    speed_limited_move(KM_MOVE_SPEED, 900, 0);      /* fastest = 0x5D */
    speed_limited_move(KM_MOVE_SPEED, 0, 300);      /* cut to 0x5D */
    speed_limited_move(KM_MOVE_STREAM, 900, 0);     /* a far 0x68 too */
    assert_true(kr_move(&r, KM_MOVE_TIME, 0, 200)); /* would need 600 deg/s */
    const run_t w = run_watch(3000);
    assert_true(w.end_ms >= 1000); /* 90 deg at 90 deg/s */
    assert_true(w.max_abs_speed <= 103500);
    near(kr_pos(&r), 0, FINAL_DDEG);
}

/* 0x19/0x1A: targets clamped to the angle limits; 0 = no limit (the
 * product travel still bounds them). */
static void test_s5_1_angle_limits_clamp_targets(void **state)
{
    (void)state;
    on_at(0);
    r.params.angle_min = -300;
    r.params.angle_max = 600;
    assert_true(kr_move(&r, KM_MOVE_SPEED, 900, 0));
    run_watch(1500);
    near(kr_pos(&r), 600, FINAL_DDEG);
    assert_true(kr_move(&r, KM_MOVE_STREAM, -32768, 0));
    run_watch(2000);
    near(kr_pos(&r), -300, FINAL_DDEG);
    r.params.angle_min = 0;
    r.params.angle_max = 0;
    assert_true(kr_move(&r, KM_MOVE_SPEED, 32767, 0));
    run_watch(2000);
    near(kr_pos(&r), 1350, FINAL_DDEG); /* travel */
}

/* 0x67 relative: adds to the target in force (not the measured position),
 * clamped the same way; absolute with time and speed. */
static void test_s5_4_advanced_relative_and_absolute(void **state)
{
    (void)state;
    on_at(0);
    r.params.angle_max = 600;
    assert_true(kr_move_rel(&r, KM_MOVE_TIME, 250, 300)); /* relative, 300 ms */
    assert_true(kr_move_rel(&r, KM_MOVE_TIME, 250, 300)); /* at once: from the target 250, not from ~0 */
    run_watch(1000);
    near(kr_pos(&r), 500, FINAL_DDEG);
    assert_true(kr_move_rel(&r, KM_MOVE_SPEED, 250, 100)); /* relative, 100 deg/s: 750 clamped to 600 */
    run_watch(1500);
    near(kr_pos(&r), 600, FINAL_DDEG);
    assert_true(kr_move_rel(&r, KM_MOVE_SPEED, -1000, 0)); /* relative, fastest */
    run_watch(1500);
    near(kr_pos(&r), -400, FINAL_DDEG);
    assert_true(kr_move(&r, KM_MOVE_TIME, 100, 400)); /* absolute, 400 ms */
    const run_t w = run_watch(1500);
    assert_true(w.end_ms >= 380 && w.end_ms <= 440);
    near(kr_pos(&r), 100, FINAL_DDEG);
    /* torque armed: relative to the measured position */
    assert_true(kr_torque(&r, 3));
    kr_run(&r, 50);
    const int32_t here = kr_pos(&r);
    assert_true(kr_move_rel(&r, KM_MOVE_TIME, -200, 300));
    run_watch(1000);
    near(kr_pos(&r), here - 200, FINAL_DDEG);
}

/* 0x11 bit 2: targets and feedback in the master's frame; the shaft turns
 * the other way. */
static void test_s5_1_direction_bit_moves_mirrored(void **state)
{
    (void)state;
    on_at(0);
    r.params.reverse = true;
    assert_true(kr_move(&r, KM_MOVE_TIME, 450, 500));
    run_watch(1500);
    near(kr_pos(&r), 450, FINAL_DDEG);
    near(km_plant_position_ddeg(&r.plant), -450, FINAL_DDEG);
}

/* 0x16 + 0x17 zero offsets: the target is where the reported position
 * reads it; the shaft sits at target - offsets. */
static void test_s5_1_zero_offsets_apply_to_targets(void **state)
{
    (void)state;
    on_at(0);
    r.params.zero_offset1 = 37;
    r.params.zero_offset2 = 100;
    kr_run(&r, 5); /* 0x46 jumped by 13.7 deg: the hold is rebased, the shaft stays */
    assert_true(kr_move(&r, KM_MOVE_TIME, 450, 500));
    run_watch(1500);
    near(kr_pos(&r), 450, FINAL_DDEG);
    near(km_plant_position_ddeg(&r.plant), 450 - 137, FINAL_DDEG);
    /* both with the direction bit: reported = -(sensor + offsets) */
    r.params.reverse = true;
    assert_true(kr_move(&r, KM_MOVE_TIME, 200, 500));
    run_watch(1500);
    near(kr_pos(&r), 200, FINAL_DDEG);
    near(km_plant_position_ddeg(&r.plant), -200 - 137, FINAL_DDEG);
}

/* §5.4 0x64 = 3 armed: off now (no PWM), the next rotation command turns
 * it on and moves. */
static void test_s5_4_armed_turns_on_at_rotation(void **state)
{
    (void)state;
    kr_init_at(&r, &km_plant_default_config, 100);
    kr_run(&r, 20);
    assert_int_equal(r.bridge.mode, KM_BRIDGE_FREE); /* power-on output: 0x11 bit 0 = 0 */
    assert_int_equal(r.ctl.servo.ts, 3);
    assert_true(kr_move(&r, KM_MOVE_TIME, 400, 300));
    assert_int_equal(r.ctl.servo.ts, 2);
    kr_tick(&r);
    assert_int_equal(r.bridge.mode, KM_BRIDGE_PWM);
    run_watch(1000);
    near(kr_pos(&r), 400, FINAL_DDEG);
}

/* §5.4 0x64 = 0 / 1 stop the motion: free (coasts, no damping) or brake;
 * bit 7 clears at once, 0x4D stops; rotation commands are refused until
 * the torque is on or armed again. 0x64 = 2 holds where it is. */
static void test_s5_4_stop_free_and_brake(void **state)
{
    (void)state;
    on_at(0);
    assert_true(kr_move(&r, KM_MOVE_SPEED, 1200, 0));
    kr_run(&r, 200);
    assert_true(r.live.running);
    assert_true(kr_torque(&r, 0));
    kr_tick(&r);
    assert_false(r.live.running);
    assert_int_equal(r.bridge.mode, KM_BRIDGE_FREE);
    const uint32_t rot = r.live.rotation_ms;
    const int32_t at_free = kr_pos(&r);
    kr_run(&r, 300);
    assert_int_equal(r.live.rotation_ms, rot);
    const int32_t coasted = kr_pos(&r) - at_free;
    assert_false(kr_move(&r, KM_MOVE_TIME, 0, 500));

    /* the same stop with brake damping: it stops in a shorter distance */
    on_at(0);
    assert_true(kr_move(&r, KM_MOVE_SPEED, 1200, 0));
    kr_run(&r, 200);
    assert_true(kr_torque(&r, 1));
    kr_tick(&r);
    assert_int_equal(r.bridge.mode, KM_BRIDGE_BRAKE);
    const int32_t at_brake = kr_pos(&r);
    kr_run(&r, 300);
    const int32_t braked = kr_pos(&r) - at_brake;
    assert_true(coasted > 0 && braked >= 0 && braked < coasted);
    assert_false(kr_move(&r, KM_MOVE_SPEED, 0, 0));
    assert_false(r.live.running);

    /* 2: on, holding the position it has now */
    assert_true(kr_torque(&r, 2));
    const int32_t here = kr_pos(&r);
    kr_run(&r, 500);
    near(kr_pos(&r), here, FINAL_DDEG);
    assert_false(r.live.running);
}

/* 0x4C deviation = reported position - target in force, while moving and
 * holding; 0 with the torque off. Zero offsets written while holding
 * rebase the hold (docs/protocol-decisions.md "Zero offsets, direction and
 * the travel"; §5.1 0x17 warns the vendor's servo jumps): 0x46 and the
 * target both move by the change, the shaft stays. */
static void test_s5_3_deviation_and_offset_rebase(void **state)
{
    (void)state;
    on_at(0);
    assert_true(kr_move(&r, KM_MOVE_TIME, -600, 800));
    kr_run(&r, 300);
    assert_int_equal(r.live.deviation, kr_pos(&r) - (-600));
    assert_true(r.live.deviation > 100);
    run_watch(1500);
    near(r.live.deviation, 0, FINAL_DDEG);
    r.params.zero_offset2 = 50; /* +5.0 deg: 0x46 reads 5 deg more at once */
    kr_tick(&r);
    near(r.live.deviation, 0, FINAL_DDEG); /* the hold is rebased: the target moved with 0x46 */
    kr_run(&r, 1000);
    near(kr_pos(&r), -550, FINAL_DDEG);                       /* the same angle, in the new frame */
    near(km_plant_position_ddeg(&r.plant), -600, FINAL_DDEG); /* the shaft did not move */
    assert_true(kr_torque(&r, 0));
    kr_tick(&r);
    assert_int_equal(r.live.deviation, 0);
}

/* Holding: against an external torque of 0.6 N.m (30 % of stall) the
 * shaft ends within 0.2 deg of the held position (the integrator takes the
 * load up), and returns there when the torque goes. */
static void test_hold_against_load(void **state)
{
    (void)state;
    on_at(300);
    r.in.ext_torque_unm = -600000; /* 0.6 N.m against */
    for (unsigned i = 0; i < 1000; i++) {
        r.in.ext_torque_unm = -600000;
        kr_tick(&r);
    }
    near(kr_pos(&r), 300, FINAL_DDEG); /* the integrator takes the load up */
    r.in.ext_torque_unm = 0;
    kr_run(&r, 1000);
    near(kr_pos(&r), 300, FINAL_DDEG);
}

/* 0x68 streams: targets on a ramp at 90 deg/s from a master at 50 Hz and
 * 100 Hz (and 45 deg/s at 50 Hz). Once under way (after 300 ms) the shaft
 * speed stays within +-5 % of the stream's: no stop-and-go. The shaft ends
 * on the last target; bit 7 clears after it. */
static void stream(uint32_t period_ms, int32_t step_ddeg, uint32_t n)
{
    on_at(-600);
    int32_t tgt = -600;
    int32_t vmin = INT32_MAX, vmax = INT32_MIN;
    uint32_t t = 0;
    for (uint32_t k = 0; k < n; k++) {
        tgt += step_ddeg;
        assert_true(kr_move(&r, KM_MOVE_STREAM, (int16_t)tgt, 0));
        for (uint32_t i = 0; i < period_ms; i++, t++) {
            kr_tick(&r);
            assert_true(r.live.running);
            const int32_t v = km_plant_speed_mdps(&r.plant);
            if (t >= 300) {
                vmin = v < vmin ? v : vmin;
                vmax = v > vmax ? v : vmax;
            }
        }
    }
    const int32_t want = step_ddeg * 100000 / (int32_t)period_ms; /* m deg/s */
    print_message("stream %u ms x %d (%d m deg/s): shaft %d..%d m deg/s after 300 ms, lag %d x 0.1 deg\n",
                  period_ms, step_ddeg, want, vmin, vmax, tgt - kr_pos(&r));
    if (vmin < want - want / 20 || vmax > want + want / 20) {
        fail_msg("stream %u ms x %d: speed %d..%d m deg/s, stream %d", period_ms, step_ddeg, vmin, vmax,
                 want);
    }
    /* the shaft is at most ~2 intervals behind the newest target */
    assert_true(tgt - kr_pos(&r) <= 2 * step_ddeg + 2);
    run_watch(500);
    near(kr_pos(&r), tgt, FINAL_DDEG);
    assert_false(r.live.running);
}

static void test_s5_4_interpolation_50hz(void **state)
{
    (void)state;
    stream(20, 18, 50); /* 90 deg/s for 1 s */
    stream(20, 9, 100); /* 45 deg/s for 2 s */
}

static void test_s5_4_interpolation_100hz(void **state)
{
    (void)state;
    stream(10, 9, 100); /* 90 deg/s for 1 s */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s5_4_move_time_45deg_500ms),
        cmocka_unit_test(test_s5_4_move_table_overshoot_bound),
        cmocka_unit_test(test_s5_4_torque_limit_5b),
        cmocka_unit_test(test_s5_4_speed_limit_5d),
        cmocka_unit_test(test_s5_1_angle_limits_clamp_targets),
        cmocka_unit_test(test_s5_4_advanced_relative_and_absolute),
        cmocka_unit_test(test_s5_1_direction_bit_moves_mirrored),
        cmocka_unit_test(test_s5_1_zero_offsets_apply_to_targets),
        cmocka_unit_test(test_s5_4_armed_turns_on_at_rotation),
        cmocka_unit_test(test_s5_4_stop_free_and_brake),
        cmocka_unit_test(test_s5_3_deviation_and_offset_rebase),
        cmocka_unit_test(test_hold_against_load),
        cmocka_unit_test(test_s5_4_interpolation_50hz),
        cmocka_unit_test(test_s5_4_interpolation_100hz),
    };
    return cmocka_run_group_tests_name("control on the plant", tests, NULL, NULL);
}
