/* SPDX-License-Identifier: Apache-2.0 */
/* Limits and frames of control on the realistic plant (issue 20 criteria
 * 5-7, defects D4 D6 D9 D11; docs/protocol.md §5.1 0x11/0x16/0x17, §5.4
 * 0x6E..0x70, §6; docs/protocol-decisions.md "Zero offsets, direction and
 * the travel", "Motor mode and the travel", "Multi-turn position and its
 * wrap"). Control stepped against the `realistic` plant at the 1 kHz tick
 * (tests/support/km_plant_rig.h); angles are the plant's true output shaft
 * in the sensor's frame unless a check says 0x46.
 *
 * Bounds and why:
 *  - D4: the pot product's travel is +-135.0 deg of the sensor; with 0x17 =
 *    +10 deg a move to -135.0 deg (master) is clamped to -125.0 deg, so the
 *    shaft stays within 0.5 deg of the sensor's -135.0 deg (the arrive band
 *    plus the plant's backlash); today it goes to -145.0 deg;
 *  - D6: a zero offset or direction change while holding moves the shaft
 *    less than 0.3 deg (the hold's own wander under the plant's sensor
 *    noise is below 0.1 deg) and draws no more than 600 mA (the hold
 *    against the 0.3 N.m load draws ~400 mA); today: a 10 deg / 60 deg jump
 *    at over 2 A;
 *  - D9: 0x70 angle/turn runs at 360 deg/s end within +-2 deg of the count
 *    (criterion 8's target), braked or free;
 *  - D11: 0x6E on the pot product stops at the travel's edge, never on the
 *    end stop (+-150 deg), drawing nothing once stopped;
 *  - the int32 wrap: positions and speeds through +2^31 x 0.1 deg are
 *    modular (no signed overflow: the host-asan build traps on one). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_plant_rig.h"

static kr_rig_t r;

/* The true output angle, 0.1 deg (sensor frame). */
static int32_t shaft_ddeg(void)
{
    return km_plant_turns_ddeg(&r.plant);
}

static int32_t iabs(int32_t v)
{
    return v < 0 ? -v : v;
}

/* The pot product on the realistic plant at rest at `pos`, torque on. */
static void rig_pot_at(int32_t pos)
{
    kr_init_at(&r, &km_plant_realistic_config, pos);
    kr_run(&r, 20);
}

/* The encoder product on the realistic plant without pot or stops, the
 * shaft at `pos` (0.1 deg, any turn count). */
static void rig_encoder_at(int32_t pos)
{
    static km_plant_config_t cfg;
    kr_init_encoder_at(&r, &cfg, &km_plant_realistic_config, pos);
    kr_run(&r, 20);
}

/* The encoder product at 0 deg. */
static void rig_encoder(void)
{
    rig_encoder_at(0);
}

/* Runs `ms` ticks; the lowest and highest shaft angle and the largest
 * |current| seen. */
static void run_watch(uint32_t ms, int32_t *lo, int32_t *hi, int32_t *peak_ma)
{
    for (uint32_t i = 0; i < ms; i++) {
        kr_tick(&r);
        const int32_t a = shaft_ddeg();
        *lo = a < *lo ? a : *lo;
        *hi = a > *hi ? a : *hi;
        const int32_t ma = iabs(km_plant_current_ma(&r.plant));
        *peak_ma = ma > *peak_ma ? ma : *peak_ma;
    }
}

/* D4: the travel moves with the zero offsets: with 0x17 = +10 deg the
 * product still never turns past its -135.0 deg of travel. */
static void test_d4_travel_moves_with_zero_offset(void **state)
{
    (void)state;
    rig_pot_at(0);
    r.params.zero_offset2 = 100;
    kr_run(&r, 5);
    assert_true(kr_torque(&r, 2));
    assert_true(kr_move(&r, KM_MOVE_SPEED, -1350, 0));
    int32_t lo = INT32_MAX, hi = INT32_MIN, peak = 0;
    run_watch(2500, &lo, &hi, &peak);
    print_message("D4 0x17 +10 deg, move to -135: shaft %d..%d, 0x46 %d, peak %d mA\n", (int)lo, (int)hi,
                  (int)kr_pos(&r), (int)peak);
    assert_true(lo >= -1355);
    assert_true(iabs(kr_pos(&r) - -1250) <= 5); /* the clamped target, master's frame */
    assert_false(r.live.running);
}

/* D4 with 0x11 bit 2: the travel is mirrored with the frame. */
static void test_d4_travel_mirrors_with_direction(void **state)
{
    (void)state;
    rig_pot_at(0);
    r.params.zero_offset2 = 100;
    r.params.reverse = true;
    kr_run(&r, 5);
    assert_true(kr_torque(&r, 2));
    assert_true(kr_move(&r, KM_MOVE_SPEED, 1350, 0)); /* master +135 = sensor -145 */
    int32_t lo = INT32_MAX, hi = INT32_MIN, peak = 0;
    run_watch(2500, &lo, &hi, &peak);
    print_message("D4 reversed: shaft %d..%d, 0x46 %d\n", (int)lo, (int)hi, (int)kr_pos(&r));
    assert_true(lo >= -1355);
    assert_true(iabs(kr_pos(&r) - 1250) <= 5);
}

/* D5: the pot reads past the travel (its ADC spans +-165 deg, the stops
 * sit at +-150, the travel is +-135: docs/protocol-decisions.md "Position
 * fault = a reading the mechanics cannot give"), so an overshoot past +135 deg is seen and corrected: a
 * full-range fastest move at twice the inertia rests within the arrive
 * band of +135.0 deg and 0x46 reads the shaft (within 0.2 deg). A
 * regression test: main already passes it since the plant's pot was
 * widened past the travel (the issue measured 5.2 deg past with 0x46 at
 * 135.0 on a pot spanning only the travel). */
static void test_d5_overshoot_past_travel_is_seen(void **state)
{
    (void)state;
    static km_plant_config_t cfg;
    cfg = km_plant_realistic_config;
    cfg.load_j_gmm2 *= 2u;
    kr_init_at(&r, &cfg, -1350);
    kr_run(&r, 20);
    assert_true(kr_torque(&r, 2));
    kr_run(&r, 300);
    assert_true(kr_move(&r, KM_MOVE_SPEED, 1350, 0));
    kr_run(&r, 2500);
    print_message("D5 -135 -> +135 at 2x inertia: shaft %d, 0x46 %d\n", (int)shaft_ddeg(), (int)kr_pos(&r));
    assert_true(iabs(shaft_ddeg() - 1350) <= 5);
    assert_true(iabs(kr_pos(&r) - shaft_ddeg()) <= 2);
}

/* Holding +30 deg against 0.3 N.m, settled. */
static void hold_loaded(void)
{
    rig_pot_at(0);
    assert_true(kr_torque(&r, 2));
    assert_true(kr_move(&r, KM_MOVE_TIME, 300, 400));
    kr_run(&r, 800);
    r.in.ext_torque_unm = -300000;
    kr_run(&r, 2000);
}

/* D6's bound: for 1.5 s after a frame change made while holding, the shaft
 * stays within 0.3 deg of `at` drawing at most 600 mA. */
static void expect_hold_stays(const char *change, int32_t at)
{
    int32_t lo = at, hi = at, peak = 0;
    run_watch(1500, &lo, &hi, &peak);
    print_message("D6 %s while holding: shaft %d..%d (was %d), peak %d mA, 0x46 %d\n", change, (int)lo,
                  (int)hi, (int)at, (int)peak, (int)kr_pos(&r));
    assert_true(hi - at <= 3 && at - lo <= 3);
    assert_true(peak <= 600);
}

/* D6: a new zero offset while holding: the shaft stays, 0x46 reads the
 * same angle in the new frame. */
static void test_d6_offset_while_holding_rebases(void **state)
{
    (void)state;
    hold_loaded();
    const int32_t at = shaft_ddeg();
    r.params.zero_offset2 = 100;
    expect_hold_stays("0x17 +10 deg", at);
    assert_true(iabs(kr_pos(&r) - 400) <= 3);
    assert_int_equal(r.live.torque_switch, 2);
}

/* D6: the direction bit flipped while holding under load: the shaft stays
 * (the integrator's push is kept, mirrored), 0x46 reads the mirror. */
static void test_d6_direction_while_holding_rebases(void **state)
{
    (void)state;
    hold_loaded();
    const int32_t at = shaft_ddeg();
    r.params.reverse = true;
    expect_hold_stays("0x11 bit 2", at);
    assert_true(iabs(kr_pos(&r) - -300) <= 3);
    /* and a move afterwards is in the new frame: -20 deg master = +20 sensor */
    assert_true(kr_move(&r, KM_MOVE_TIME, -200, 300));
    kr_run(&r, 1500);
    assert_true(iabs(shaft_ddeg() - 200) <= 5);
}

/* D6 mid-move: the move ends at the set-point of that tick, still running
 * (bit 7) until the shaft is there; no step. */
static void test_d6_offset_mid_move_no_step(void **state)
{
    (void)state;
    rig_pot_at(0);
    assert_true(kr_torque(&r, 2));
    kr_run(&r, 300);
    assert_true(kr_move(&r, KM_MOVE_TIME, 900, 1000));
    kr_run(&r, 400);
    r.params.zero_offset2 = -100;
    int32_t lo = INT32_MAX, hi = INT32_MIN, peak = 0;
    run_watch(1000, &lo, &hi, &peak);
    print_message("D6 0x17 -10 deg mid-move: shaft %d..%d, peak %d mA\n", (int)lo, (int)hi, (int)peak);
    assert_true(peak <= 2265); /* never above the plant's stall current */
    assert_true(hi <= 900);
    assert_false(r.live.running);
    assert_true(iabs(kr_pos(&r) - (shaft_ddeg() - 100)) <= 5);
}

/* Criterion 5: with 0x5D = 180 deg/s, 0x5B = 700 and 0x5C = 1000 mA, a
 * move of 120 deg asked in 300 ms (faster than 0x5D allows): the shaft's
 * 10 ms mean speed never above 180 deg/s (today's main: 189), the bridge
 * PWM never above 700, the current above 1100 mA for at most 5 ms. */
static void test_c5_speed_limit_bounds_the_shaft(void **state)
{
    (void)state;
    rig_pot_at(-600);
    r.params.speed_limit_dps = 180;
    r.params.torque_limit = 700;
    r.params.current_limit_ma = 1000;
    assert_true(kr_torque(&r, 2));
    kr_run(&r, 300);
    assert_true(kr_move(&r, KM_MOVE_TIME, 600, 300));
    int32_t fastest = 0, pwm_max = 0, over_run = 0, over_max = 0;
    int32_t window[10] = {0}; /* the last 10 ticks' shaft speeds, m deg/s */
    for (uint32_t i = 0; i < 1500u; i++) {
        kr_tick(&r);
        window[i % 10u] = km_plant_speed_mdps(&r.plant);
        int32_t sum = 0;
        for (unsigned k = 0; k < 10u; k++) {
            sum += window[k] / 10;
        }
        fastest = i >= 10u && iabs(sum) > fastest ? iabs(sum) : fastest;
        pwm_max = iabs(r.bridge.pwm) > pwm_max ? iabs(r.bridge.pwm) : pwm_max;
        over_run = km_plant_step_peak_ma(&r.plant) > 1100 ? over_run + 1 : 0;
        over_max = over_run > over_max ? over_run : over_max;
    }
    print_message("C5 0x5D 180: fastest %d m deg/s, PWM %d, above 0x5C+10 %% for %d ms\n", (int)fastest,
                  (int)pwm_max, (int)over_max);
    assert_true(fastest <= 180000);
    assert_true(pwm_max <= 700);
    assert_true(over_max <= 5);
    assert_true(iabs(shaft_ddeg() - 600) <= 5);
}

/* Criterion 5, 0x5C while holding: a settled hold at +60 deg after a move
 * in time (0x5B 700,
 * 0x5C 1000 mA, 0x5D 180) pushed by half the stall torque (0.875 N.m: it
 * takes ~1.15 A to hold, more than 0x5C allows) for 1.5 s, then let go
 * for 0.5 s. The current stays within 0x5C + 10 % but for at most 5 ms
 * at a time (today's main: 23 ms at up to 1.2 A: the hold's push
 * integrator kept raising the PWM while the current was over 0x5C, and
 * the current limiter's cap, wound up at 1000 during the quiet hold, took
 * that long to close; docs/tuning.md "Current limit"). */
static void test_c5_current_limit_holds_against_a_push(void **state)
{
    (void)state;
    rig_pot_at(0);
    r.params.speed_limit_dps = 180;
    r.params.torque_limit = 700;
    r.params.current_limit_ma = 1000;
    assert_true(kr_torque(&r, 2));
    kr_run(&r, 300);
    assert_true(kr_move(&r, KM_MOVE_TIME, 600, 300));
    kr_run(&r, 900); /* the move, then the hold settles */
    int32_t over_run = 0, over_max = 0, peak = 0;
    for (uint32_t i = 0; i < 2000u; i++) {
        r.in.ext_torque_unm = i < 1500u ? -875000 : 0;
        kr_tick(&r);
        const int32_t ma = km_plant_step_peak_ma(&r.plant);
        peak = ma > peak ? ma : peak;
        over_run = ma > 1100 ? over_run + 1 : 0;
        over_max = over_run > over_max ? over_run : over_max;
    }
    print_message("C5 0x5C 1000 mA against 0.875 N.m: above 1100 mA for %d ms at most, peak %d mA\n",
                  (int)over_max, (int)peak);
    assert_true(over_max <= 5);
}

/* Criterion 6: for criterion 3's six moves on the realistic plant, the
 * shaft is inside the arrive band (0.5 deg) at the tick bit 7 clears
 * (today's main: 0.546 deg on one of them). */
static void test_c6_bit7_clears_inside_the_band(void **state)
{
    (void)state;
    static const struct {
        km_move_kind_t kind;
        int16_t from, to;
        uint16_t param;
    } moves[] = {
        {KM_MOVE_TIME, 0, 900, 500}, {KM_MOVE_TIME, 0, 300, 300}, {KM_MOVE_TIME, 0, -900, 1000},
        {KM_MOVE_SPEED, 0, 900, 0},  {KM_MOVE_SPEED, 0, 50, 0},   {KM_MOVE_SPEED, 0, -150, 120},
    };
    int32_t worst = 0;
    for (unsigned k = 0; k < sizeof moves / sizeof moves[0]; k++) {
        rig_pot_at(moves[k].from);
        assert_true(kr_torque(&r, 2));
        kr_run(&r, 1500);
        assert_true(kr_move(&r, moves[k].kind, moves[k].to, moves[k].param));
        kr_tick(&r);
        assert_true(r.live.running);
        uint32_t t = 0;
        while (r.live.running && t < 5000u) {
            kr_tick(&r);
            t++;
        }
        const int32_t off = iabs((int32_t)(km_plant_shaft_udeg(&r.plant) / 1000) - moves[k].to * 100);
        print_message("C6 move %u: bit 7 cleared after %u ms, shaft %d m deg off\n", k, (unsigned)t,
                      (int)off);
        worst = off > worst ? off : worst;
    }
    assert_true(worst <= 500);
}

/* 0x70 at 360 deg/s until `amount` (`until`), then `after`: where the
 * shaft ends, 1 s after bit 7 cleared. */
static int32_t counted_run(km_run_until_t until, uint16_t amount, km_run_after_t after)
{
    rig_encoder();
    assert_true(kr_run_motor(&r, KM_RUN_SPEED, false, 360, until, amount, after));
    kr_tick(&r); /* bit 7 reads with the next tick's live values */
    assert_true(r.live.running);
    uint32_t t = 0;
    while (r.live.running && t < 20000u) {
        kr_tick(&r);
        t++;
    }
    assert_false(r.live.running);
    kr_run(&r, 1000);
    return shaft_ddeg();
}

/* D9: counted runs slow down before their count and stop on it. */
static void test_d9_counted_runs_stop_on_the_count(void **state)
{
    (void)state;
    const int32_t a720 = counted_run(KM_UNTIL_ANGLE, 720, KM_AFTER_BRAKE);
    const int32_t t30 = counted_run(KM_UNTIL_TURNS, 30, KM_AFTER_BRAKE);
    const int32_t a90 = counted_run(KM_UNTIL_ANGLE, 90, KM_AFTER_FREE);
    print_message("D9 720 deg brake: %d, 3.0 turns brake: %d, 90 deg free: %d (x0.1 deg)\n", (int)a720,
                  (int)t30, (int)a90);
    assert_true(iabs(a720 - 7200) <= 20);
    assert_true(iabs(t30 - 10800) <= 20);
    assert_true(iabs(a90 - 900) <= 20);
}

/* D11: 0x6E on the pot product stops at the travel's edge (+135.0 deg),
 * not on the end stop; a run away from the edge is taken. */
static void test_d11_pot_motor_stops_at_travel(void **state)
{
    (void)state;
    rig_pot_at(0);
    assert_true(kr_motor_signed(&r, KM_RUN_PWM, 400));
    int32_t lo = INT32_MAX, hi = INT32_MIN, peak = 0;
    run_watch(3000, &lo, &hi, &peak);
    const int32_t ma = iabs(km_plant_current_ma(&r.plant));
    print_message("D11 0x6E 400: shaft up to %d, end stop %d, now %d mA\n", (int)hi,
                  (int)km_plant_at_endstop(&r.plant), (int)ma);
    assert_true(hi <= 1350 + 20);
    assert_false(km_plant_at_endstop(&r.plant));
    assert_true(ma <= 20);
    assert_false(r.live.running);
    assert_true(kr_motor_signed(&r, KM_RUN_PWM, -400));
    kr_run(&r, 300);
    assert_true(r.live.running);
    assert_true(shaft_ddeg() < hi - 100);
}

/* D11 for 0x6F-like speed runs is the same path; the encoder product has
 * no travel edge: 0x6E runs on (multi-turn). */
static void test_d11_encoder_runs_on(void **state)
{
    (void)state;
    rig_encoder();
    assert_true(kr_motor_signed(&r, KM_RUN_PWM, 600));
    kr_run(&r, 3000);
    assert_true(r.live.running);
    assert_true(shaft_ddeg() > 3000);
}

/* D7: the encoder product switched on holding at `at` (0.1 deg, any turn
 * count), settled 0.5 s, then `load_unm` on the output for 3 s. *defl is
 * the largest deflection, *rest where the shaft ends, both from where it
 * held before the load (modular: the short way round, 0.1 deg). */
static void hold_at_turns(int32_t at, int32_t load_unm, int32_t *defl, int32_t *rest)
{
    rig_encoder_at(at);
    assert_true(kr_torque(&r, 2));
    kr_run(&r, 500);
    const int32_t held = shaft_ddeg();
    assert_true(iabs(km_pos_diff(held, at)) <= 2);
    r.in.ext_torque_unm = load_unm;
    *defl = 0;
    for (int i = 0; i < 3000; i++) {
        kr_tick(&r);
        const int32_t d = iabs(km_pos_diff(shaft_ddeg(), held));
        *defl = d > *defl ? d : *defl;
    }
    *rest = km_pos_diff(shaft_ddeg(), held);
}

/* D7 and criterion 7 ("the same holding at any turn count"): under 0.3 N.m
 * the encoder product holds at 150,000 deg, at -150,000 deg and either
 * side of the int32 wrap (the load pushing the shaft through it) as it
 * holds at 0 under the same load: it rests off by at most one count (the
 * encoder's 0.1 deg) more and deflects at most 0.2 deg more than there
 * (at 0: 0.5 deg, resting 0.3 deg off after 3 s). Today the position loop and
 * the profile clamp at +-100,000 deg: the error reads 0 beyond and the
 * shaft creeps away under the load. */
static void test_d7_hold_at_any_turn_count(void **state)
{
    (void)state;
    static const struct {
        int32_t at, load_unm;
    } cases[] = {
        {1500000, -300000},      {1500000, 300000},        {-1500000, 300000},
        {INT32_MAX - 2, 300000}, {INT32_MIN + 2, -300000}, {999990, 300000},
    };
    int32_t ref_defl[2], ref_rest[2]; /* at 0: the load negative, positive */
    hold_at_turns(0, -300000, &ref_defl[0], &ref_rest[0]);
    hold_at_turns(0, 300000, &ref_defl[1], &ref_rest[1]);
    print_message("D7 hold at 0 under -/+0.3 N.m: deflection %d/%d, rest %d/%d (0.1 deg)\n", (int)ref_defl[0],
                  (int)ref_defl[1], (int)ref_rest[0], (int)ref_rest[1]);
    for (unsigned k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        int32_t defl, rest;
        hold_at_turns(cases[k].at, cases[k].load_unm, &defl, &rest);
        const unsigned ref = cases[k].load_unm > 0 ? 1u : 0u;
        print_message("D7 hold at %ld under %+ld uN.m: deflection %d, rest %d (0.1 deg)\n", (long)cases[k].at,
                      (long)cases[k].load_unm, (int)defl, (int)rest);
        assert_true(iabs(km_pos_diff(kr_pos(&r), shaft_ddeg())) <= 2); /* 0x46 reads the shaft */
        assert_true(iabs(rest) <= iabs(ref_rest[ref]) + 1);
        assert_true(defl <= ref_defl[ref] + 2);
    }
}

/* D7: relative moves (0x67) of +90 deg and back across +-100,000 deg and
 * through the int32 wrap end on their targets (within 0.5 deg, bit 7
 * clear, 0x46 reading the shaft), as the same move does at 0. */
static void test_d7_move_across_turn_counts(void **state)
{
    (void)state;
    static const int32_t from[] = {0, 999550, -1000450, INT32_MAX - 450};
    for (unsigned k = 0; k < sizeof from / sizeof from[0]; k++) {
        rig_encoder_at(from[k]);
        assert_true(kr_torque(&r, 2));
        kr_run(&r, 300);
        const int32_t there = km_pos_add(from[k], 900);
        assert_true(kr_move_rel(&r, KM_MOVE_TIME, 900, 500));
        kr_run(&r, 1500);
        print_message("D7 +90 deg from %ld: shaft %ld, 0x46 %ld, bit 7 %d\n", (long)from[k],
                      (long)shaft_ddeg(), (long)kr_pos(&r), (int)r.live.running);
        assert_true(iabs(km_pos_diff(shaft_ddeg(), there)) <= 5);
        assert_true(iabs(km_pos_diff(kr_pos(&r), there)) <= 5);
        assert_false(r.live.running);
        assert_true(kr_move_rel(&r, KM_MOVE_TIME, -900, 500));
        kr_run(&r, 1500);
        assert_true(iabs(km_pos_diff(shaft_ddeg(), from[k])) <= 5);
        assert_false(r.live.running);
    }
}

/* D7 in the profile alone: a set-point at any turn count stays where it
 * is put, and a move from 150,000 deg or through the wrap arrives on its
 * target (docs/protocol-decisions.md "Multi-turn position and its wrap"). */
static void test_d7_profile_at_any_turn_count(void **state)
{
    (void)state;
    static const int32_t from[] = {1500000, -1500000, INT32_MAX, INT32_MIN, INT32_MAX - 450};
    for (unsigned k = 0; k < sizeof from / sizeof from[0]; k++) {
        km_profile_t p;
        km_profile_reset(&p, from[k]);
        assert_int_equal(km_profile_pos_ddeg(&p), from[k]);
        const int32_t to = km_pos_add(from[k], 900);
        km_profile_move(&p, to, 360 * KM_PROFILE_UPS_PER_DPS, 20000);
        int ms = 0;
        while (!km_profile_step(&p, 1000u) && ms < 5000) {
            ms++;
        }
        assert_true(p.done);
        assert_int_equal(km_profile_pos_ddeg(&p), to);
    }
}

/* A synthetic encoder reading 4 counts per tick through +2^31 x 0.1 deg
 * (wrapping, as km_turn_counter's int32 does) under a 0x6F run with the
 * stall protection armed and a zero offset: 0x46 wraps, the speeds stay
 * 400 deg/s, no signed overflow anywhere in the tick. */
static void test_wrap_tick_is_defined(void **state)
{
    (void)state;
    km_control_params_t p;
    kr_default_params(&p);
    p.variant = KM_VARIANT_ENCODER;
    p.travel_min = INT16_MIN;
    p.travel_max = INT16_MAX;
    p.angle_min = 0;
    p.angle_max = 0;
    p.zero_offset2 = 1000;
    p.prot_enable = 0x0F;
    p.stall_pwm = 1;
    p.stall_time_100ms = 50;
    p.current_trip_ma = 3000;
    p.current_time_100ms = 50;
    p.voltage_high_v = 20;
    p.voltage_low_v = 1;
    p.temp_trip_c = 100;
    static km_control_t c;
    km_control_init(&c, &p);
    km_sensors_t s;
    memset(&s, 0, sizeof s);
    s.voltage_mv = 7400;
    s.temperature_c10 = 250;
    s.current_ma = 300;
    uint32_t raw = 0x7FFFFFFFu - 1000u - 600u;
    km_live_t live;
    km_bridge_t bridge;
    s.position = (int32_t)raw;
    km_control_step(&c, &s, &p, 1000u, &live, &bridge);
    km_request_t q;
    memset(&q, 0, sizeof q);
    q.kind = KM_REQ_MOTOR;
    q.u.run.mode = KM_RUN_SPEED;
    q.u.run.value = 400;
    assert_true(km_control_request(&c, &q, &p));
    int32_t last = live.position;
    bool wrapped = false;
    for (int k = 0; k < 400; k++) {
        raw += 4u;
        s.position = raw <= 0x7FFFFFFFu ? (int32_t)raw : -(int32_t)(~raw) - 1;
        km_control_step(&c, &s, &p, 1000u, &live, &bridge);
        const uint32_t step = (uint32_t)live.position - (uint32_t)last;
        assert_int_equal(step, 4u);
        wrapped = wrapped || live.position < last;
        last = live.position;
        if (k >= 30) {
            assert_true(live.speed >= 390 && live.speed <= 410);
        }
    }
    assert_true(wrapped);
    assert_true(live.running);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_d4_travel_moves_with_zero_offset),
        cmocka_unit_test(test_d4_travel_mirrors_with_direction),
        cmocka_unit_test(test_d5_overshoot_past_travel_is_seen),
        cmocka_unit_test(test_d6_offset_while_holding_rebases),
        cmocka_unit_test(test_d6_direction_while_holding_rebases),
        cmocka_unit_test(test_d6_offset_mid_move_no_step),
        cmocka_unit_test(test_c5_speed_limit_bounds_the_shaft),
        cmocka_unit_test(test_c5_current_limit_holds_against_a_push),
        cmocka_unit_test(test_c6_bit7_clears_inside_the_band),
        cmocka_unit_test(test_d9_counted_runs_stop_on_the_count),
        cmocka_unit_test(test_d11_pot_motor_stops_at_travel),
        cmocka_unit_test(test_d11_encoder_runs_on),
        cmocka_unit_test(test_wrap_tick_is_defined),
        cmocka_unit_test(test_d7_profile_at_any_turn_count),
        cmocka_unit_test(test_d7_hold_at_any_turn_count),
        cmocka_unit_test(test_d7_move_across_turn_counts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
