/* SPDX-License-Identifier: Apache-2.0 */
/* The control modules one by one, without the plant: the trajectory
 * generator (control/km_profile.c), the position loop, the output stage,
 * the speed estimators and the target clamp of servo mode. Units as in
 * each header (profile: u = 0.001 x 0.1 deg, u/s). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_output.h"
#include "km_position_loop.h"
#include "km_profile.h"
#include "km_servo_mode.h"
#include "km_speed_est.h"

#define DPS KM_PROFILE_UPS_PER_DPS

/* Runs a profile to the end at 1 ms ticks; checks it never passes the
 * target, never exceeds vmax, and changes speed by at most accel per tick
 * (+1 for the carried remainder). Returns the ticks it took. */
static uint32_t run_profile(km_profile_t *p, int32_t from_u, int32_t accel, bool check_accel)
{
    const int32_t target = p->target;
    const bool up = target >= from_u;
    int32_t last_v = p->vel;
    uint32_t t = 0;
    while (!km_profile_step(p, 1000)) {
        t++;
        assert_true(t < 200000u);
        assert_true(up ? p->pos <= target : p->pos >= target);
        assert_true(p->vel <= p->vmax && p->vel >= -p->vmax);
        const int32_t dv = p->vel - last_v;
        if (check_accel && (dv > accel + 1 || dv < -accel - 1)) {
            fail_msg("tick %u: speed step %d u/s, accel bound %d", t, dv, accel);
        }
        last_v = p->vel;
    }
    assert_int_equal(p->pos, target);
    assert_int_equal(p->vel, 0);
    return t + 1u;
}

/* A move from rest: time-optimal trapezoid (or triangle) under vmax and
 * accel; the time matches the closed form within 3 ms + 2 % (the last
 * crawl onto the target is cut short by the snap of the final piece). */
static void test_profile_move_trapezoid_and_triangle(void **state)
{
    (void)state;
    static const struct {
        int32_t from, to, vmax_dps, accel_dps2;
    } t[] = {
        {0, 900, 90, 4000},   {0, -900, 360, 4000},      {100, 105, 360, 4000},
        {0, 3600, 360, 1000}, {-1350, 1350, 720, 20000}, {0, 1, 1, 10},
    };
    for (unsigned i = 0; i < sizeof t / sizeof t[0]; i++) {
        km_profile_t p;
        km_profile_reset(&p, t[i].from);
        const int32_t accel = t[i].accel_dps2 * 10; /* u/s per ms */
        km_profile_move(&p, t[i].to, t[i].vmax_dps * DPS, accel);
        const uint32_t ms = run_profile(&p, t[i].from * 1000, accel, true);
        /* closed form, ms: trapezoid D/v + v/a, triangle 2 sqrt(D/a) */
        const double d = (t[i].to > t[i].from ? t[i].to - t[i].from : t[i].from - t[i].to) / 10.0;
        const double v = t[i].vmax_dps, a = t[i].accel_dps2;
        double want = d / v + v / a;
        if (d < v * v / a) {
            double x = d / a, s = x;
            for (int k = 0; k < 40; k++)
                s = 0.5 * (s + x / s); /* sqrt, no libm */
            want = 2.0 * s;
        }
        want *= 1000.0;
        if ((double)ms < want - 3.0 - 0.02 * want || (double)ms > want + 3.0 + 0.02 * want) {
            fail_msg("move %u: %u ms, closed form %.1f ms", i, ms, want);
        }
    }
}

/* A move in time T from rest ends in T (+-2 ms) when the speed limit allows,
 * and at the speed limit otherwise. */
static void test_profile_move_time(void **state)
{
    (void)state;
    static const struct {
        int32_t to;
        uint32_t ms;
        int32_t vlim_dps;
        uint32_t want_lo, want_hi;
    } t[] = {
        {450, 500, 360, 498, 503},     {-900, 1000, 360, 998, 1003}, {2, 50, 360, 48, 53},
        {1200, 2000, 360, 1998, 2003}, {900, 200, 90, 1000, 1300}, /* needs 600 deg/s: 90 deg/s wins */
    };
    for (unsigned i = 0; i < sizeof t / sizeof t[0]; i++) {
        km_profile_t p;
        km_profile_reset(&p, 0);
        km_profile_move_time(&p, t[i].to, t[i].ms, t[i].vlim_dps * DPS);
        const uint32_t ms = run_profile(&p, 0, 0, false);
        if (ms < t[i].want_lo || ms > t[i].want_hi) {
            fail_msg("move %u: %u ms, want %u..%u", i, ms, t[i].want_lo, t[i].want_hi);
        }
    }
}

/* A new move during a move starts from the set-point and speed it has:
 * no jump in position, speed changes by at most accel per tick. */
static void test_profile_retarget_blends(void **state)
{
    (void)state;
    km_profile_t p;
    km_profile_reset(&p, 0);
    const int32_t accel = 40000;
    km_profile_move(&p, 900, 360 * DPS, accel);
    for (int i = 0; i < 100; i++) {
        (void)km_profile_step(&p, 1000);
    }
    const int32_t pos = p.pos, vel = p.vel;
    assert_true(vel > 0);
    km_profile_move(&p, -300, 360 * DPS, accel); /* reverse */
    assert_int_equal(p.pos, pos);
    assert_int_equal(p.vel, vel);
    (void)km_profile_step(&p, 1000);
    assert_true(p.vel >= vel - accel - 1);
    (void)run_profile(&p, 900 * 1000, accel, true); /* may pass -300's side? no: it comes back */
    assert_int_equal(km_profile_pos_ddeg(&p), -300);
}

/* Stream: the interpolator settles at the stream speed; the next
 * target arrives before the set-point stops. */
static void test_profile_stream_constant_speed(void **state)
{
    (void)state;
    km_profile_t p;
    km_profile_reset(&p, 0);
    int32_t tgt = 0;
    for (int k = 0; k < 50; k++) {
        tgt += 18;
        km_profile_stream(&p, tgt, 20000, 360 * DPS, 5000);
        for (int i = 0; i < 20; i++) {
            (void)km_profile_step(&p, 1000);
            if (k >= 40) { /* from rest the interpolator catches up its lag first (~0.75 s at 500 deg/s^2,
                            * the last 0.5 deg at 1/128 ms: docs/tuning.md) */
                /* 90 deg/s = 900,000 u/s, within 1 % once settled */
                assert_true(p.vel >= 891000 && p.vel <= 909000);
                assert_false(p.done);
            }
        }
    }
    /* the stream stops: the last segment ends on the last target (the lag,
     * then braking at KM_PROFILE_STREAM_ACCEL_DIV x 500 deg/s^2) */
    for (int i = 0; i < 200; i++) {
        (void)km_profile_step(&p, 1000);
    }
    assert_true(p.done);
    assert_int_equal(km_profile_pos_ddeg(&p), tgt);
}

static km_control_gains_t gains(void)
{
    const km_control_gains_t g = KM_CONTROL_GAINS_DEFAULT;
    return g;
}

/* Position loop: sign of each term, the output bound, the integrator only
 * while holding and not past saturation. */
static void test_position_loop_terms_and_bounds(void **state)
{
    (void)state;
    km_control_gains_t g = gains();
    km_position_loop_t l;
    km_position_loop_init(&l);
    km_position_loop_in_t in = {.setpoint_u = 10000,
                                .setpoint_ddps = 0,
                                .position = 0,
                                .speed_ddps = 0,
                                .pwm_max = 1000,
                                .integrate = false};
    /* kp only: 10 x 0.1 deg error at 10 PWM per 0.1 deg = 100 */
    assert_int_equal(km_position_loop_step(&l, &g, &in, 1000), g.kp_q8 * 10 / 256);
    in.setpoint_u = -10000;
    assert_int_equal(km_position_loop_step(&l, &g, &in, 1000), -(int32_t)(g.kp_q8 * 10 / 256));
    /* bound */
    in.setpoint_u = 10000000;
    in.pwm_max = 300;
    assert_int_equal(km_position_loop_step(&l, &g, &in, 1000), 300);
    /* speed feedforward at constant set-point speed: kv x v + friction (+ kd x speed error) */
    km_position_loop_init(&l);
    in.pwm_max = 1000;
    in.setpoint_u = 0;
    in.setpoint_ddps = 900;
    in.speed_ddps = 900;
    (void)km_position_loop_step(&l, &g, &in, 1000); /* the first tick also has the acceleration term */
    assert_int_equal(km_position_loop_step(&l, &g, &in, 1000), g.kv_q8 * 90 / 256 + g.friction_pwm);
    /* integrator: not while moving; while holding it grows, bounded by i_max */
    km_position_loop_init(&l);
    in.setpoint_ddps = 0;
    in.speed_ddps = 0;
    in.setpoint_u = 20000;
    const int32_t p_only = km_position_loop_step(&l, &g, &in, 1000);
    assert_int_equal(l.i_acc, 0);
    in.integrate = true;
    g.i_max_pwm = 400; /* below the output bound, so the integrator's own bound shows */
    int32_t out = 0;
    for (int i = 0; i < 100000; i++) {
        out = km_position_loop_step(&l, &g, &in, 1000);
    }
    assert_int_equal(out, p_only + g.i_max_pwm);
    /* saturated: it does not grow past the bound of the output */
    km_position_loop_init(&l);
    in.setpoint_u = 1000000;
    in.pwm_max = 500;
    for (int i = 0; i < 1000; i++) {
        (void)km_position_loop_step(&l, &g, &in, 1000);
    }
    assert_int_equal(l.i_acc, 0);
}

/* A settled hold pushed 5 deg away with a 2 ms tick: ki_hold grown by the
 * error (x 4.9) times the error times dt passes 2^31 before the division by
 * 100; the step must still push back, by exactly ki x e / 10 x dt / 100. */
static void test_position_loop_hold_integral_no_overflow(void **state)
{
    (void)state;
    const km_control_gains_t g = gains();
    km_position_loop_t l;
    km_position_loop_init(&l);
    l.still_ms = KM_HOLD_SETTLED_MS;
    l.rest_pos = 0;
    const km_position_loop_in_t in = {
        .setpoint_u = 0, .position = -51, .pwm_max = 1000, .integrate = true, .still = true};
    (void)km_position_loop_step(&l, &g, &in, 2000u);
    const int64_t e_d = 51 - (int64_t)g.hold_band_ddeg; /* the band is a dead band */
    const int64_t ki = (int64_t)g.ki_hold_q4 * 16;
    const int64_t ki_grown = ki + ((ki * e_d * KM_HOLD_KI_GROW_Q6) >> 6);
    assert_true(ki_grown * e_d / 10 * 2000 > INT32_MAX); /* the case this test is for */
    assert_int_equal(l.i_acc, (int32_t)(ki_grown * e_d / 10 * 2000 / 100));
}

/* Output stage: direction flips the PWM into the sensor's frame, the limit
 * clamps it, free and brake carry no PWM; 0x49 reports |PWM|. */
static void test_output_direction_limit_modes(void **state)
{
    (void)state;
    km_bridge_t b = km_output_bridge(KM_BRIDGE_PWM, 700, 500, false);
    assert_int_equal(b.mode, KM_BRIDGE_PWM);
    assert_int_equal(b.pwm, 500);
    b = km_output_bridge(KM_BRIDGE_PWM, 700, 500, true);
    assert_int_equal(b.pwm, -500);
    assert_int_equal(km_output_pwm_reported(&b), 500);
    b = km_output_bridge(KM_BRIDGE_PWM, -200, 1000, true);
    assert_int_equal(b.pwm, 200);
    b = km_output_bridge(KM_BRIDGE_PWM, -5000, 4000, false);
    assert_int_equal(b.pwm, -1000);
    b = km_output_bridge(KM_BRIDGE_BRAKE, 700, 1000, false);
    assert_int_equal(b.mode, KM_BRIDGE_BRAKE);
    assert_int_equal(b.pwm, 0);
    assert_int_equal(km_output_pwm_reported(&b), 0);
    b = km_output_bridge(KM_BRIDGE_FREE, -700, 1000, true);
    assert_int_equal(b.mode, KM_BRIDGE_FREE);
    assert_int_equal(b.pwm, 0);
}

/* The loop's speed estimate: position change over the last 8 ticks. */
static void test_speed_fast_estimator(void **state)
{
    (void)state;
    km_speed_fast_t f;
    int32_t pos = 100;
    km_speed_fast_init(&f, pos);
    int32_t v = 0;
    for (int i = 0; i < 20; i++) {
        pos += 3; /* 0.3 deg per ms = 300 deg/s = 3000 0.1 deg/s */
        v = km_speed_fast_step(&f, pos, 1000);
    }
    assert_int_equal(v, 3000);
    for (int i = 0; i < 8; i++) {
        v = km_speed_fast_step(&f, pos, 1000);
    }
    assert_int_equal(v, 0);
    for (int i = 0; i < 16; i++) {
        pos -= 1; /* 0.1 deg per 2 ms = -50 deg/s */
        v = km_speed_fast_step(&f, pos, 2000);
    }
    assert_int_equal(v, -500);
}

/* Servo-mode target clamp: travel always, 0x19/0x1A when non-zero. */
static void test_servo_mode_clamp(void **state)
{
    (void)state;
    km_control_params_t p;
    memset(&p, 0, sizeof p);
    p.travel_min = -1350;
    p.travel_max = 1350;
    assert_int_equal(km_servo_mode_clamp(&p, 2000), 1350);
    assert_int_equal(km_servo_mode_clamp(&p, -2000), -1350);
    assert_int_equal(km_servo_mode_clamp(&p, 12), 12);
    p.angle_min = -300;
    p.angle_max = 600;
    assert_int_equal(km_servo_mode_clamp(&p, 900), 600);
    assert_int_equal(km_servo_mode_clamp(&p, -900), -300);
    p.angle_min = 0; /* no minimum: the travel bounds it */
    assert_int_equal(km_servo_mode_clamp(&p, -900), -900);
    assert_int_equal(km_servo_mode_clamp(&p, -32768), -1350);
}

/* Ticks of other lengths than 1 ms (a late tick re-basing the app's grid,
 * a caller with another period; control/km_profile.c prv_dv's general
 * path): speeding up from rest far from the target, the speed after each
 * piece is exactly floor(accel x elapsed us / 1000), the remainder carried,
 * for every accel shape and tick length. */
static void test_profile_other_ticks_speed_exact(void **state)
{
    (void)state;
    static const uint32_t dts[] = {1000u, 999u,  1001u, 996u, 1004u, 1003u, 997u, 1000u,
                                   2000u, 1500u, 1005u, 995u, 1u,    998u,  1002u};
    static const int32_t accels[] = {1, 7, 999, 1000, 1001, 9601, 123457, 1000000};
    for (size_t a = 0; a < sizeof accels / sizeof accels[0]; a++) {
        km_profile_t p;
        km_profile_reset(&p, 0);
        km_profile_move(&p, 800000, 0x3FFFFFFF, accels[a]); /* 80,000 deg away: no braking */
        int64_t us = 0;
        for (size_t k = 0; k < sizeof dts / sizeof dts[0]; k++) {
            (void)km_profile_step(&p, dts[k]);
            us += dts[k];
            assert_int_equal(p.vel, (int32_t)((int64_t)accels[a] * us / 1000));
        }
    }
}

/* 0x4D's clock counts whole ms of a motion whatever the ticks' lengths
 * (control/km_servo_mode.c prv_count_rotation: a late tick of several ms
 * as well as ticks a few us off 1 ms). */
static void test_servo_mode_rotation_clock(void **state)
{
    (void)state;
    km_control_params_t p;
    memset(&p, 0, sizeof p);
    p.torque_switch = KM_TORQUE_ON;
    p.travel_min = -1350;
    p.travel_max = 1350;
    p.gains.accel_dps2 = 4000u;
    p.gains.fastest_dps = 360u;
    p.gains.settle_ms = 60000u;
    km_servo_mode_t m;
    km_servo_mode_init(&m, &p);
    const km_move_t mv = {.kind = KM_MOVE_TIME, .target = 900, .time_or_speed = 30000u, .pwm_cap = 1000u};
    assert_true(km_servo_mode_move(&m, &mv, &p, 0));
    static const uint32_t dts[] = {1000u, 999u, 1001u, 2500u, 999u, 3999u, 1u, 1000u, 65000u, 1003u, 997u};
    uint32_t us = 0;
    for (size_t k = 0; k < sizeof dts / sizeof dts[0]; k++) {
        km_servo_mode_out_t out;
        km_servo_mode_step(&m, &p, 0, 0, dts[k], &out);
        us += dts[k];
        assert_int_equal(m.rotation_ms, us / 1000u);
        assert_int_equal(m.rotation_rem_us, us % 1000u);
    }
}

/* Extremes from the wire stay defined (the sanitizer build of this test,
 * and the fuzz_servo target, would trip on an overflow): the widest i16
 * targets in 1 ms, speed limits up to 65535 deg/s, streams at any
 * interval, far positions and gains at their maximum in the loop. */
static void test_extremes_stay_bounded(void **state)
{
    (void)state;
    static const int32_t targets[] = {-32768, 32767, 0, 1, -1};
    static const uint32_t times[] = {1, 2, 3, 4, 65535};
    static const int32_t vlims[] = {1, 10000, 65535 * DPS};
    for (unsigned a = 0; a < 5; a++) {
        for (unsigned b = 0; b < 5; b++) {
            for (unsigned c = 0; c < 3; c++) {
                km_profile_t p;
                km_profile_reset(&p, targets[(a + 1u) % 5u]);
                km_profile_move_time(&p, targets[a], times[b], vlims[c]);
                for (int i = 0; i < 50; i++) {
                    (void)km_profile_step(&p, 1000);
                }
                km_profile_stream(&p, targets[b], times[b] * 1000u, vlims[c], 5000);
                (void)km_profile_step(&p, 4000000000u);
                km_profile_stream(&p, targets[a], 0, vlims[c], 5000);
                (void)km_profile_step(&p, 1000);
                km_profile_move(&p, targets[b], vlims[c], 2000000000);
                (void)km_profile_step(&p, 1000);
                assert_true(p.vel <= p.vmax && p.vel >= -p.vmax);
            }
        }
    }
    km_profile_t far;
    km_profile_reset(&far, INT32_MAX);
    assert_int_equal(km_profile_pos_ddeg(&far), INT32_MAX); /* kept at any turn count (D7) */
    km_control_gains_t g;
    memset(&g, 0xFF, sizeof g);
    km_position_loop_t l;
    km_position_loop_init(&l);
    static const int32_t pos[] = {INT32_MIN, INT32_MAX, 0};
    for (unsigned i = 0; i < 3; i++) {
        for (unsigned j = 0; j < 3; j++) {
            km_position_loop_in_t in = {.setpoint_u = pos[i],
                                        .setpoint_ddps = pos[j],
                                        .position = pos[j],
                                        .speed_ddps = pos[i],
                                        .pwm_max = 1000,
                                        .integrate = true};
            const int32_t out = km_position_loop_step(&l, &g, &in, i == 0 ? 0xFFFFFFFFu : 1000u);
            assert_true(out >= -1000 && out <= 1000);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_profile_move_trapezoid_and_triangle),
        cmocka_unit_test(test_profile_move_time),
        cmocka_unit_test(test_profile_retarget_blends),
        cmocka_unit_test(test_profile_stream_constant_speed),
        cmocka_unit_test(test_position_loop_terms_and_bounds),
        cmocka_unit_test(test_position_loop_hold_integral_no_overflow),
        cmocka_unit_test(test_output_direction_limit_modes),
        cmocka_unit_test(test_speed_fast_estimator),
        cmocka_unit_test(test_servo_mode_clamp),
        cmocka_unit_test(test_profile_other_ticks_speed_exact),
        cmocka_unit_test(test_servo_mode_rotation_clock),
        cmocka_unit_test(test_extremes_stay_bounded),
    };
    return cmocka_run_group_tests_name("control modules", tests, NULL, NULL);
}
