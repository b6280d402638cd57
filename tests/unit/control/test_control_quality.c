/* SPDX-License-Identifier: Apache-2.0 */
/* Issue 20's control defects, each driven through the real control tick
 * against the plant (tests/support/km_plant_rig.h): the realistic plant
 * (sensor noise, friction, backlash; docs/plant.md) where the defect needs
 * it. docs/protocol.md §5.4 (rotation commands), docs/tuning.md. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_plant_rig.h"
#include "stream_rig.h"

static kr_rig_t r;

/* |v| */
static int32_t iabs(int32_t v)
{
    return v < 0 ? -v : v;
}

/* Torque on at `pos` on the named plant, settled 500 ms. */
static void on_at(const char *plant, int32_t pos)
{
    kr_init_at(&r, km_plant_config_named(plant), pos);
    assert_true(kr_torque(&r, 2));
    kr_run(&r, 500);
}

/* D2: holding on the realistic plant (pot noise), the bridge PWM does not
 * buzz: fewer than 10 sign changes a second over 4 s, and 0x46 moves by
 * at most one count. */
static void test_d2_quiet_hold_under_sensor_noise(void **state)
{
    (void)state;
    on_at("realistic", 0);
    assert_true(kr_move(&r, KM_MOVE_TIME, 100, 300));
    kr_run(&r, 1500);
    int32_t last_sign = 0, flips = 0, lo = INT32_MAX, hi = INT32_MIN;
    for (int i = 0; i < 4000; i++) {
        kr_tick(&r);
        const int32_t s = r.bridge.pwm > 0 ? 1 : (r.bridge.pwm < 0 ? -1 : 0);
        if (s != 0 && last_sign != 0 && s != last_sign) {
            flips++;
        }
        last_sign = s != 0 ? s : last_sign;
        lo = kr_pos(&r) < lo ? kr_pos(&r) : lo;
        hi = kr_pos(&r) > hi ? kr_pos(&r) : hi;
    }
    print_message("hold: %d PWM sign changes in 4 s, 0x46 %d..%d\n", flips, lo, hi);
    assert_true(flips < 40);
    assert_true(hi - lo <= 1);
}

/* D1: 0x65 +90 deg in 500 ms retargeted at 250 ms to +60 deg in 500 ms
 * (realistic plant): no overshoot past +60 deg beyond 0.3 deg, never more
 * than the stall current, and bit 7 clears 500 ms +-10 % after the retarget. */
static void test_d1_retarget_is_smooth_and_on_time(void **state)
{
    (void)state;
    on_at("realistic", 0);
    assert_true(kr_move(&r, KM_MOVE_TIME, 900, 500));
    kr_run(&r, 250);
    assert_true(kr_move(&r, KM_MOVE_TIME, 600, 500));
    int32_t peak = 0, end = -1;
    int64_t top = INT64_MIN;
    for (int i = 0; i < 1500; i++) {
        kr_tick(&r);
        peak = iabs(km_plant_current_ma(&r.plant)) > peak ? iabs(km_plant_current_ma(&r.plant)) : peak;
        top = km_plant_shaft_udeg(&r.plant) > top ? km_plant_shaft_udeg(&r.plant) : top;
        if (end < 0 && !r.live.running) {
            end = i + 1;
        }
    }
    print_message("retarget: peak %d mA, top %lld udeg, bit 7 clears after %d ms\n", peak, (long long)top,
                  end);
    assert_true(top <= 60300000);
    assert_true(peak <= 2265);
    assert_true(end >= 450 && end <= 550);
}

/* D10: a fastest move under a 0x67 PWM cap of 100 creeps; bit 7 stays set
 * while the shaft still moves and clears only once it arrived (or stopped). */
static void test_d10_blocked_shaft_clock_waits_for_a_moving_shaft(void **state)
{
    (void)state;
    on_at("ideal", 0);
    assert_true(kr_move_capped(&r, 900, 100));
    kr_run(&r, 5);
    for (int i = 0; i < 6000 && r.live.running; i++) {
        kr_tick(&r);
        if (!r.live.running) {
            break;
        }
    }
    print_message("capped move: bit 7 cleared at 0x46 = %d\n", kr_pos(&r));
    assert_false(r.live.running);
    assert_true(kr_pos(&r) >= 900 - 50);
}

/* D8: a speed limit above the product's fastest (0x5D = 720) still caps the
 * profile at fastest_dps: a fastest move never asks for more. */
static void test_d8_profile_capped_at_product_fastest(void **state)
{
    (void)state;
    on_at("ideal", -900);
    r.params.speed_limit_dps = 720;
    assert_true(kr_move(&r, KM_MOVE_TIME, 900, 200)); /* 180 deg in 200 ms: 1200 deg/s asked */
    int32_t vmax = 0;
    for (int i = 0; i < 1500; i++) {
        kr_tick(&r);
        vmax = iabs(r.ctl.servo.profile.vel) > vmax ? iabs(r.ctl.servo.profile.vel) : vmax;
    }
    assert_true(vmax <= (int32_t)r.params.gains.fastest_dps * KM_PROFILE_UPS_PER_DPS);
}

/* The streams' jitter generator: the 100 Hz test goes on from the 50 Hz one's. */
static uint32_t s_lcg = 12345u;

/* D2b: 0x68 at `period` ms, 90 deg/s from -60 to +60 deg, each frame up to
 * +-5 ms off its time, one in 17 dropped (realistic plant): from 300 ms to
 * the last frame the shaft's 10 ms mean speed stays within +-10 % of the
 * stream's, and the current never exceeds 1 A (the steps of the old
 * acceleration feedforward drew 3.5 A). */
static void stream_checked(uint32_t period)
{
    on_at("realistic", -600);
    sr_stream_t s;
    sr_start(&s, period, &s_lcg);
    int32_t vmin = INT32_MAX, vmax = INT32_MIN, peak = 0;
    while (sr_step(&s, &r)) {
        if (s.at_ms >= 300u) {
            vmin = s.speed_mdps < vmin ? s.speed_mdps : vmin;
            vmax = s.speed_mdps > vmax ? s.speed_mdps : vmax;
            peak = iabs(km_plant_current_ma(&r.plant)) > peak ? iabs(km_plant_current_ma(&r.plant)) : peak;
        }
    }
    print_message("stream %u ms: shaft %d..%d m deg/s (90000), peak %d mA\n", period, vmin, vmax, peak);
    assert_true(vmin >= 81000 && vmax <= 99000);
    assert_true(peak <= 1000);
}

static void test_d2b_stream_50hz_jitter_and_drops(void **state)
{
    (void)state;
    stream_checked(20u);
}

static void test_d2b_stream_100hz_jitter_and_drops(void **state)
{
    (void)state;
    stream_checked(10u);
}

/* D3: holding against 1.0 N.m (about 55 % of the realistic plant's stall
 * torque, more than the old integrator bound could hold), the shaft comes
 * back within 0.2 deg of the target. */
static void test_d3_hold_against_heavy_load(void **state)
{
    (void)state;
    on_at("realistic", 0);
    r.in.ext_torque_unm = 1000000;
    kr_run(&r, 3000);
    int64_t sum = 0;
    for (int i = 0; i < 1000; i++) {
        kr_tick(&r);
        sum += km_plant_shaft_udeg(&r.plant);
    }
    const int64_t mean = sum / 1000;
    print_message("hold against 1.0 N.m: shaft %lld udeg\n", (long long)mean);
    assert_true(mean <= 200000 && mean >= -200000);
}

/* Criterion 2's load step (issue 20, docs/control-quality.md): holding 0
 * on the realistic plant, a load of 30 % of its stall torque (1.75 N.m
 * measured by the bench: 0.525 N.m) comes at once; the shaft is back
 * within 0.2 deg, and stays there, in 200 ms at most (212 ms with a push
 * integrator that did not grow with the error; docs/tuning.md). */
static void test_c2_load_step_back_within_200ms(void **state)
{
    (void)state;
    on_at("realistic", 0);
    assert_true(kr_move(&r, KM_MOVE_TIME, 0, 200));
    kr_run(&r, 1500);
    r.in.ext_torque_unm = 525000;
    int32_t last_out = 0;
    int64_t peak = 0;
    for (int i = 0; i < 1500; i++) {
        kr_tick(&r);
        const int64_t at = km_plant_shaft_udeg(&r.plant);
        peak = at > peak ? at : peak;
        last_out = at > 200000 || at < -200000 ? i + 1 : last_out;
    }
    print_message("load step 30 %%: deflection %lld mdeg, back within 0.2 deg after %d ms\n",
                  (long long)(peak / 1000), last_out);
    assert_true(peak <= 1500000);
    assert_true(last_out <= 200);
}

/* Criterion 7's hold after a fast stop (issue 20, docs/control-quality.md;
 * docs/protocol.md §5.4 0x6F, §5.1 0x64 = 2 "hold current position"): the
 * encoder product on the realistic plant runs 0x6F at 360 deg/s, then
 * 0x6F 0 and 0x64 = 2 at the same tick. The shaft coasts ~3.5 deg past
 * the held position and comes back; from 500 ms after the stop it stays
 * put (the bench's wrap row: within 0.5 deg; on the code before, the
 * integrator wound up by the return left the shaft 0.9 deg past the hold
 * and crept back 0.6 deg over the next second). */
static void test_c7_hold_after_a_fast_stop_stays(void **state)
{
    (void)state;
    static km_plant_config_t cfg; /* the plant keeps a pointer to it */
    cfg = km_plant_realistic_config;
    cfg.pot_travel_ddeg = 0;
    cfg.endstop_ddeg = 0;
    kr_init_at(&r, &cfg, 0);
    r.encoder = true;
    r.params.variant = KM_VARIANT_ENCODER;
    r.params.travel_min = INT16_MIN;
    r.params.travel_max = INT16_MAX;
    r.params.angle_min = 0;
    r.params.angle_max = 0;
    kr_run(&r, 20);
    assert_true(kr_motor_signed(&r, KM_RUN_SPEED, 360));
    kr_run(&r, 2000);
    assert_true(kr_motor_signed(&r, KM_RUN_SPEED, 0));
    assert_true(kr_torque(&r, 2));
    kr_run(&r, 500);
    int64_t lo = INT64_MAX, hi = INT64_MIN;
    for (int i = 0; i < 1500; i++) {
        kr_tick(&r);
        const int64_t at = km_plant_shaft_udeg(&r.plant);
        lo = at < lo ? at : lo;
        hi = at > hi ? at : hi;
    }
    print_message("hold after a 360 deg/s stop: the shaft moves %lld mdeg from 500 ms to 2 s\n",
                  (long long)((hi - lo) / 1000));
    assert_true(hi - lo <= 200000);
}

/* Holding `target` (0.1 deg) on the realistic plant, `load_unm` on the
 * shaft for 3 s, then let go: the most the shaft goes past the target
 * (mdeg, the way the released hold pushes) in the 2.5 s after, and in
 * *end_mdeg how far from the target it rests then. `stall_hold`: 0x32
 * stall on, 0x33 bit 3 (released by command only), 0x34 stall = hold,
 * 0x3F 600 PWM for 2.0 s, as the bus's protect scenario sets them. */
static int32_t spring_after_release(int32_t target, int32_t load_unm, bool stall_hold, int32_t *end_mdeg)
{
    kr_init_at(&r, km_plant_config_named("realistic"), 0);
    if (stall_hold) {
        r.params.prot_enable = KM_PROT_STALL;
        r.params.prot_release = KM_PROT_STALL;
        r.params.prot_state = 0x80u; /* 0x34 bits 7:6 = 10: hold */
        r.params.stall_pwm = 600;
        r.params.stall_time_100ms = 20;
    }
    assert_true(kr_torque(&r, 2));
    assert_true(kr_move(&r, KM_MOVE_TIME, (int16_t)target, 400));
    kr_run(&r, 1500);
    r.in.ext_torque_unm = load_unm;
    kr_run(&r, 3000);
    assert_true(r.live.protecting == stall_hold); /* the stall tripped: its hold holds */
    r.in.ext_torque_unm = 0;
    const int64_t way = load_unm < 0 ? 1 : -1;
    int64_t past = INT64_MIN;
    for (int i = 0; i < 2500; i++) {
        kr_tick(&r);
        const int64_t at = way * (km_plant_shaft_udeg(&r.plant) - (int64_t)target * 100000);
        past = at > past ? at : past;
    }
    *end_mdeg = (int32_t)((km_plant_shaft_udeg(&r.plant) - (int64_t)target * 100000) / 1000);
    return (int32_t)(past / 1000);
}

/* A load held at the drive's limit and let go (docs/tuning.md "A load let
 * go"): 1.0 to 3.0 N.m on the held shaft (2.0 and 3.0 more than the motor
 * lifts at 0x14's 2 A, ~1.6 N.m: the drive stands at the current limit),
 * then none. The integrator held the load; once the shaft stands past
 * the target the way it pushes, it bleeds, so the shaft goes at most
 * 2.5 deg past (1.1-2.2 deg) and rests within 0.2 deg 2.5 s later
 * (before the bleed: 2.1-3.3 deg past, resting up to 0.55 deg off).
 * Up to ~1.6 deg of it is the gear train's own wind-up springing back
 * within the first ms (docs/plant.md), which no control can catch. */
static void test_hold_let_go_after_a_load_at_the_limit(void **state)
{
    (void)state;
    static const int32_t rows[][2] = {{0, -2000000}, {300, -2000000}, {0, 2000000}, {300, 2000000},
                                      {0, -1500000}, {0, -1000000},   {0, -3000000}};
    int32_t worst = 0, worst_end = 0;
    for (unsigned k = 0; k < sizeof rows / sizeof rows[0]; k++) {
        int32_t end = 0;
        const int32_t past = spring_after_release(rows[k][0], rows[k][1], false, &end);
        print_message("hold at %d, %d uN.m let go: %d mdeg past the target, resting %d mdeg off\n",
                      (int)rows[k][0], (int)rows[k][1], (int)past, (int)end);
        worst = past > worst ? past : worst;
        worst_end = iabs(end) > worst_end ? iabs(end) : worst_end;
    }
    assert_true(worst <= 2500);
    assert_true(worst_end <= 200);
}

/* The same under a stall protection's hold (0x34 stall = hold, released by
 * command: docs/protocol.md §5.2): the integrator stops growing where the
 * stall tripped, but it may shrink, so once the load goes the shaft goes
 * at most 2.2 deg past the target (1.7-1.9 deg) and is back within 0.3
 * deg while the protection still holds (before: the integrator was frozen
 * both ways and the shaft stood 4.5-7.4 deg past until a 0x36 clear). */
static void test_stall_hold_let_go_comes_back(void **state)
{
    (void)state;
    static const int32_t loads[] = {-2000000, 2000000, -1500000, -3000000};
    int32_t worst = 0, worst_end = 0;
    for (unsigned k = 0; k < sizeof loads / sizeof loads[0]; k++) {
        int32_t end = 0;
        const int32_t past = spring_after_release(0, loads[k], true, &end);
        print_message("stall hold, %d uN.m let go: %d mdeg past the target, resting %d mdeg off\n",
                      (int)loads[k], (int)past, (int)end);
        assert_true(r.live.protecting); /* still the protection's hold */
        worst = past > worst ? past : worst;
        worst_end = iabs(end) > worst_end ? iabs(end) : worst_end;
    }
    assert_true(worst <= 2200);
    assert_true(worst_end <= 300);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_d2_quiet_hold_under_sensor_noise),
        cmocka_unit_test(test_d1_retarget_is_smooth_and_on_time),
        cmocka_unit_test(test_d10_blocked_shaft_clock_waits_for_a_moving_shaft),
        cmocka_unit_test(test_d8_profile_capped_at_product_fastest),
        cmocka_unit_test(test_d2b_stream_50hz_jitter_and_drops),
        cmocka_unit_test(test_d2b_stream_100hz_jitter_and_drops),
        cmocka_unit_test(test_d3_hold_against_heavy_load),
        cmocka_unit_test(test_c2_load_step_back_within_200ms),
        cmocka_unit_test(test_c7_hold_after_a_fast_stop_stays),
        cmocka_unit_test(test_hold_let_go_after_a_load_at_the_limit),
        cmocka_unit_test(test_stall_hold_let_go_comes_back),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
