/* SPDX-License-Identifier: Apache-2.0 */
/* Plant model tests: each checks one physical behaviour against the
 * parameters (not against numbers read back from the model), so a wrong
 * equation, unit or sign fails. Doubles are fine here: the host computes the
 * expected physics, the plant itself is fixed-point. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <cmocka.h>

#include "km_plant.h"

#define PI 3.14159265358979323846

static const km_plant_input_t k_coast = {KM_PLANT_COAST, 0, 0};
static const km_plant_input_t k_brake = {KM_PLANT_BRAKE, 0, 0};

static km_plant_input_t drive(int16_t pwm)
{
    km_plant_input_t in = {KM_PLANT_DRIVE, pwm, 0};
    return in;
}

/* Run for ms milliseconds at the 1 ms control tick. */
static void run_ms(km_plant_t *p, const km_plant_input_t *in, uint32_t ms)
{
    for (uint32_t i = 0; i < ms; i++) {
        km_plant_step(p, in, 1000);
    }
}

/* Default servo with no end-stops and no pot limit: free multi-turn shaft. */
static km_plant_config_t free_shaft_config(void)
{
    km_plant_config_t c = km_plant_default_config;
    c.endstop_ddeg = 0;
    c.pot_travel_ddeg = 0;
    return c;
}

/* Ideal no-load output speed, °/s: back-EMF equals the supply. */
static double ideal_no_load_dps(const km_plant_config_t *c, double volts)
{
    double ke_out = c->motor_ke_uv_s_rad * 1e-6 * c->gear_ratio; /* V per rad/s at output */
    return volts / ke_out * 180.0 / PI;
}

static void test_at_rest_nothing_moves(void **state)
{
    (void)state;
    km_plant_t p;
    assert_true(km_plant_init(&p, &km_plant_default_config));
    km_plant_input_t zero = drive(0);
    const km_plant_input_t *ins[] = {&zero, &k_coast, &k_brake};
    for (unsigned k = 0; k < 3; k++) {
        run_ms(&p, ins[k], 10000);
        assert_int_equal(km_plant_position_ddeg(&p), 0);
        assert_int_equal(km_plant_turns_ddeg(&p), 0);
        assert_int_equal(km_plant_speed_mdps(&p), 0);
        assert_int_equal(km_plant_current_ma(&p), 0);
        assert_int_equal(km_plant_voltage_mv(&p), km_plant_default_config.supply_mv);
        assert_int_equal(km_plant_temp_dc(&p), km_plant_default_config.ambient_dc);
    }
}

/* Small PWM below the Coulomb friction does not move the shaft either. */
static void test_small_pwm_held_by_friction(void **state)
{
    (void)state;
    const km_plant_config_t *c = &km_plant_default_config;
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    /* stall torque at duty d: d * V/(R+Rint) * Kt * ratio * eff; pick d whose
     * torque is half the Coulomb friction */
    double t_full = c->supply_mv / (double)(c->motor_r_mohm + c->supply_r_mohm) * c->motor_ke_uv_s_rad *
                    c->gear_ratio * c->gear_eff_pct / 100.0; /* µN·m */
    int16_t pwm = (int16_t)(1000.0 * 0.5 * c->coulomb_unm / t_full);
    assert_true(pwm > 0);
    km_plant_input_t in = drive(pwm);
    run_ms(&p, &in, 2000);
    assert_int_equal(km_plant_speed_mdps(&p), 0);
    assert_int_equal(km_plant_turns_ddeg(&p), 0);
    assert_true(km_plant_current_ma(&p) > 0); /* stalled, drawing current */
}

static void test_full_pwm_reaches_no_load_speed_both_signs(void **state)
{
    (void)state;
    km_plant_config_t c = free_shaft_config();
    km_plant_t p;
    for (int sign = -1; sign <= 1; sign += 2) {
        assert_true(km_plant_init(&p, &c));
        km_plant_input_t in = drive((int16_t)(sign * 1000));
        run_ms(&p, &in, 1000);
        double dps = km_plant_speed_mdps(&p) / 1000.0;
        double ideal = ideal_no_load_dps(&c, c.supply_mv / 1000.0);
        /* friction costs a few %: within 10 % below the EMF limit, never above */
        assert_true(sign * dps > 0.90 * ideal);
        assert_true(sign * dps < ideal);
        /* datasheet: 0.16 s/60° = 375 °/s, ±10 % */
        assert_true(sign * dps > 375.0 * 0.9 && sign * dps < 375.0 * 1.1);
        assert_int_equal(km_plant_speed_dps(&p), (int32_t)lround(dps));
        /* no-load current is small but drives the same way */
        assert_true(sign * km_plant_current_ma(&p) > 0);
        assert_true(sign * km_plant_current_ma(&p) < 200);
        /* position advanced in the same direction by about speed * time */
        assert_true(sign * km_plant_turns_ddeg(&p) > 0);
    }
}

/* Half PWM gives about half the speed (speed follows voltage). */
static void test_half_pwm_half_speed(void **state)
{
    (void)state;
    km_plant_config_t c = free_shaft_config();
    km_plant_t p;
    assert_true(km_plant_init(&p, &c));
    km_plant_input_t full = drive(1000);
    run_ms(&p, &full, 1000);
    int32_t w_full = km_plant_speed_mdps(&p);
    assert_true(km_plant_init(&p, &c));
    km_plant_input_t half = drive(500);
    run_ms(&p, &half, 1000);
    int32_t w_half = km_plant_speed_mdps(&p);
    assert_true(w_half > w_full * 45 / 100 && w_half < w_full * 52 / 100);
}

static uint32_t ms_to_stop(const km_plant_input_t *stop_in)
{
    km_plant_config_t c = free_shaft_config();
    km_plant_t p;
    assert_true(km_plant_init(&p, &c));
    km_plant_input_t in = drive(1000);
    run_ms(&p, &in, 500);
    assert_true(km_plant_speed_mdps(&p) > 300000);
    uint32_t ms = 0;
    while (km_plant_speed_mdps(&p) != 0 && ms < 100000) {
        km_plant_step(&p, stop_in, 1000);
        ms++;
    }
    return ms;
}

static void test_brake_stops_faster_than_coast(void **state)
{
    (void)state;
    uint32_t brake = ms_to_stop(&k_brake);
    uint32_t coast = ms_to_stop(&k_coast);
    assert_true(brake < 100000);
    assert_true(coast < 100000); /* friction stops a coasting shaft too */
    assert_true(brake * 3 < coast);
}

static void test_endstop_stalls_at_v_over_r(void **state)
{
    (void)state;
    const km_plant_config_t *c = &km_plant_default_config;
    km_plant_t p;
    for (int sign = -1; sign <= 1; sign += 2) {
        assert_true(km_plant_init(&p, c));
        km_plant_input_t in = drive((int16_t)(sign * 1000));
        run_ms(&p, &in, 2000);
        assert_true(km_plant_at_endstop(&p));
        assert_int_equal(km_plant_turns_ddeg(&p), sign * c->endstop_ddeg);
        /* the stops lie inside the pot's electrical range: it reads them,
         * clear of its rails (a rail is an open wiper) */
        assert_true(c->pot_travel_ddeg > c->endstop_ddeg);
        assert_int_equal(km_plant_position_ddeg(&p), sign * c->endstop_ddeg);
        assert_int_equal(km_plant_pot_adc(&p), sign < 0 ? 186 : 3909); /* docs/protocol-decisions.md */
        assert_int_equal(km_plant_speed_mdps(&p), 0);
        double v = km_plant_voltage_mv(&p);
        double i = sign * km_plant_current_ma(&p);
        double want = v / c->motor_r_mohm * 1000.0; /* mA */
        assert_true(fabs(i - want) < 0.01 * want + 2);
        double want_total = c->supply_mv * 1000.0 / (c->motor_r_mohm + c->supply_r_mohm);
        assert_true(fabs(i - want_total) < 0.01 * want_total + 2);
        /* ~2.5 A for the default servo */
        assert_true(i > 2300 && i < 2700);
    }
}

static void test_voltage_sags_under_load(void **state)
{
    (void)state;
    const km_plant_config_t *c = &km_plant_default_config;
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    km_plant_input_t in = drive(1000);
    km_plant_step(&p, &in, 1000); /* first ms: shaft nearly still, big current */
    run_ms(&p, &in, 2000);        /* then stalled on the end-stop */
    int32_t v = km_plant_voltage_mv(&p);
    int32_t i = km_plant_supply_ma(&p);
    assert_true(i > 2000);
    int32_t sag = c->supply_mv - v;
    int32_t want = i * c->supply_r_mohm / 1000;
    assert_true(abs(sag - want) <= 3);
    assert_true(sag > 300);
    /* coasting: no load, no sag */
    run_ms(&p, &k_coast, 10);
    assert_int_equal(km_plant_voltage_mv(&p), c->supply_mv);
    /* a settable low supply gives proportionally less stall current */
    km_plant_set_supply_mv(&p, c->supply_mv / 2);
    run_ms(&p, &in, 10);
    assert_true(abs(km_plant_supply_ma(&p) * 2 - i) < 20);
}

static void test_temperature_rises_under_stall_and_relaxes(void **state)
{
    (void)state;
    const km_plant_config_t *c = &km_plant_default_config;
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    km_plant_input_t in = drive(1000);
    run_ms(&p, &in, 60000);
    double i = km_plant_current_ma(&p) / 1000.0;
    double pw = i * i * c->motor_r_mohm / 1000.0;
    double rth = c->thermal_r_mc_per_w / 1000.0;
    double tau = rth * c->thermal_c_mj_per_c / 1000.0;
    double want = c->ambient_dc / 10.0 + pw * rth * (1.0 - exp(-60.0 / tau));
    double got = km_plant_temp_dc(&p) / 10.0;
    assert_true(fabs(got - want) < 0.03 * (want - c->ambient_dc / 10.0));
    assert_int_equal(km_plant_temp_c(&p), (int32_t)lround(km_plant_temp_dc(&p) / 10.0));
    /* idle: relaxes to ambient with the same time constant */
    double hot = got;
    run_ms(&p, &k_coast, 60000);
    double cool_want = c->ambient_dc / 10.0 + (hot - c->ambient_dc / 10.0) * exp(-60.0 / tau);
    double cool = km_plant_temp_dc(&p) / 10.0;
    assert_true(fabs(cool - cool_want) < 0.03 * (hot - c->ambient_dc / 10.0));
    run_ms(&p, &k_coast, 600000);
    assert_true(abs(km_plant_temp_dc(&p) - c->ambient_dc) <= 2);
    /* settable ambient */
    km_plant_set_ambient_dc(&p, 700);
    run_ms(&p, &k_coast, 600000);
    assert_true(abs(km_plant_temp_dc(&p) - 700) <= 2);
}

static void test_external_torque(void **state)
{
    (void)state;
    km_plant_config_t c = free_shaft_config();
    km_plant_t p;
    /* below friction: holds */
    assert_true(km_plant_init(&p, &c));
    km_plant_input_t in = {KM_PLANT_COAST, 0, (int32_t)c.coulomb_unm / 2};
    run_ms(&p, &in, 1000);
    assert_int_equal(km_plant_speed_mdps(&p), 0);
    /* above friction, coasting: back-driven in the torque's direction, speed
     * limited by viscous friction only: w = (T - Tc) / b */
    in.ext_torque_unm = -(int32_t)c.coulomb_unm * 2;
    run_ms(&p, &in, 20000);                                       /* J / b ~ 3 s: settled */
    double want = -(double)c.coulomb_unm / c.viscous_unm_per_dps; /* °/s */
    if (want < -KM_PLANT_SPEED_MAX_MDPS / 1000.0) {
        want = -KM_PLANT_SPEED_MAX_MDPS / 1000.0;
    }
    double got = km_plant_speed_mdps(&p) / 1000.0;
    assert_true(got < 0);
    assert_true(fabs(got - want) < 0.05 * fabs(want));
    assert_int_equal(km_plant_current_ma(&p), 0);
    /* braked: the shorted motor resists, much slower; current opposes motion */
    in.bridge = KM_PLANT_BRAKE;
    run_ms(&p, &in, 2000);
    double braked = km_plant_speed_mdps(&p) / 1000.0;
    assert_true(braked < 0 && braked > got / 10.0);
    assert_true(km_plant_current_ma(&p) > 0);
    /* against full drive, a torque above stall torque pushes the shaft back */
    assert_true(km_plant_init(&p, &c));
    km_plant_input_t push = {KM_PLANT_DRIVE, 1000, -3000000}; /* 3 N·m > ~2 N·m stall */
    run_ms(&p, &push, 1000);
    assert_true(km_plant_speed_mdps(&p) < 0);
    assert_true(km_plant_current_ma(&p) > 2500); /* more than stall: EMF adds to supply */
}

/* One hour at full stall, and one hour spinning free: no overflow, steady heat. */
static void test_long_runs_no_overflow(void **state)
{
    (void)state;
    const km_plant_config_t *c = &km_plant_default_config;
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    km_plant_input_t in = drive(1000);
    int32_t last_t = km_plant_temp_dc(&p);
    for (uint32_t s = 0; s < 3600; s++) {
        run_ms(&p, &in, 1000);
        assert_true(km_plant_temp_dc(&p) >= last_t);
        last_t = km_plant_temp_dc(&p);
    }
    assert_true(km_plant_at_endstop(&p));
    double i = km_plant_current_ma(&p) / 1000.0;
    double steady = c->ambient_dc / 10.0 + i * i * c->motor_r_mohm / 1000.0 * c->thermal_r_mc_per_w / 1000.0;
    assert_true(fabs(km_plant_temp_dc(&p) / 10.0 - steady) < 0.02 * steady);
    assert_int_equal(p.time_ms, 3600000);

    km_plant_config_t fc = free_shaft_config();
    assert_true(km_plant_init(&p, &fc));
    int32_t last = 0;
    for (uint32_t s = 0; s < 3600; s++) {
        run_ms(&p, &in, 1000);
        assert_true(km_plant_turns_ddeg(&p) > last);
        last = km_plant_turns_ddeg(&p);
    }
    double dps = km_plant_speed_mdps(&p) / 1000.0;
    double want = dps * 3600.0 * 10.0; /* 0.1° */
    assert_true(fabs(last - want) < 0.01 * want);
}

static bool same_state(const km_plant_t *x, const km_plant_t *y)
{
    return x->pos_ddeg == y->pos_ddeg && x->pos_rem_ndeg == y->pos_rem_ndeg &&
           x->speed_mdps == y->speed_mdps && x->current_ma == y->current_ma && x->supply_ma == y->supply_ma &&
           x->bus_mv == y->bus_mv && x->temp_uc == y->temp_uc && x->carry_us == y->carry_us &&
           x->time_ms == y->time_ms && x->time_us_part == y->time_us_part;
}

static void test_deterministic_and_dt_independent(void **state)
{
    (void)state;
    km_plant_t a, b, d;
    assert_true(km_plant_init(&a, &km_plant_default_config));
    assert_true(km_plant_init(&b, &km_plant_default_config));
    assert_true(km_plant_init(&d, &km_plant_default_config));
    km_plant_input_t in = drive(700);
    for (int k = 0; k < 300; k++) {
        km_plant_step(&a, &in, 1000);
        for (int j = 0; j < 4; j++) {
            km_plant_step(&b, &in, 250);
        }
        km_plant_step(&d, &in, 300);
        km_plant_step(&d, &in, 700);
    }
    assert_true(same_state(&a, &b));
    assert_true(same_state(&a, &d));
    assert_true(km_plant_turns_ddeg(&a) > 0);
}

/* The encoder product's sensor: the angle within one turn in 4096 counts. */
static void test_encoder_counts_within_one_turn(void **state)
{
    (void)state;
    km_plant_t p;
    assert_true(km_plant_init(&p, &km_plant_default_config));
    const struct {
        int32_t ddeg;
        uint16_t counts;
    } rows[] = {
        {0, 0},      {900, 1024},  {1800, 2048}, {3599, 4095},   {3600, 0},
        {3700, 114}, {-100, 3982}, {-3600, 0},   {-36100, 3982},
    };
    for (size_t i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        km_plant_set_position_ddeg(&p, rows[i].ddeg);
        assert_int_equal(km_plant_encoder_counts(&p), rows[i].counts);
    }
}

/* A restart of the MCU leaves the physics as they are: a plant restored from
 * another's physics runs on exactly as the original (bridge inputs equal). */
static void test_physics_survive_a_restart(void **state)
{
    (void)state;
    km_plant_t a;
    km_plant_t b;
    assert_true(km_plant_init(&a, &km_plant_default_config));
    assert_true(km_plant_init(&b, &km_plant_default_config));
    km_plant_set_supply_mv(&a, 6500);
    km_plant_set_ambient_dc(&a, 400);
    const km_plant_input_t drive = {.bridge = KM_PLANT_DRIVE, .pwm = 700, .ext_torque_unm = 0};
    km_plant_step(&a, &drive, 300000); /* 300 ms: turning fast and warm */
    km_plant_physics_t ph;
    km_plant_get_physics(&a, &ph);
    km_plant_set_physics(&b, &ph);
    assert_int_equal(km_plant_turns_ddeg(&b), km_plant_turns_ddeg(&a));
    assert_int_equal(km_plant_speed_mdps(&b), km_plant_speed_mdps(&a));
    assert_int_equal(km_plant_temp_dc(&b), km_plant_temp_dc(&a));
    assert_true(km_plant_speed_dps(&b) > 100);
    /* the bridge is off across a reset: both coast from here alike */
    const km_plant_input_t coast = {.bridge = KM_PLANT_COAST, .pwm = 0, .ext_torque_unm = 0};
    km_plant_t a2 = a;
    km_plant_physics_t ph2;
    km_plant_get_physics(&a2, &ph2);
    km_plant_set_physics(&a2, &ph2); /* a's own state, current dropped */
    km_plant_step(&a2, &coast, 200000);
    km_plant_step(&b, &coast, 200000);
    assert_int_equal(km_plant_turns_ddeg(&b), km_plant_turns_ddeg(&a2));
    assert_int_equal(km_plant_voltage_mv(&b), km_plant_voltage_mv(&a2));
    assert_int_equal(km_plant_temp_dc(&b), km_plant_temp_dc(&a2));
}

static void test_faults(void **state)
{
    (void)state;
    const km_plant_config_t *c = &km_plant_default_config;
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    assert_int_equal(km_plant_pot_adc(&p), (KM_PLANT_POT_ADC_MAX + 1) / 2);
    km_plant_set_faults(&p, KM_PLANT_FAULT_POT_OPEN);
    assert_int_equal(km_plant_pot_adc(&p), KM_PLANT_POT_ADC_MAX);
    assert_int_equal(km_plant_position_ddeg(&p), c->pot_travel_ddeg);
    km_plant_set_faults(&p, KM_PLANT_FAULT_MOTOR_OPEN | KM_PLANT_FAULT_TEMP_OPEN);
    km_plant_input_t in = drive(1000);
    run_ms(&p, &in, 1000);
    assert_int_equal(km_plant_current_ma(&p), 0);
    assert_int_equal(km_plant_turns_ddeg(&p), 0);
    assert_int_equal(km_plant_temp_dc(&p), KM_PLANT_TEMP_OPEN_DC);
    km_plant_set_faults(&p, 0);
    assert_int_equal(km_plant_temp_dc(&p), c->ambient_dc);
    run_ms(&p, &in, 10);
    assert_true(km_plant_current_ma(&p) > 0);
    /* pot ADC tracks position over the travel */
    km_plant_set_position_ddeg(&p, -c->pot_travel_ddeg);
    assert_int_equal(km_plant_pot_adc(&p), 0);
    km_plant_set_position_ddeg(&p, c->pot_travel_ddeg);
    assert_int_equal(km_plant_pot_adc(&p), KM_PLANT_POT_ADC_MAX);
}

static void test_init_rejects_bad_config(void **state)
{
    (void)state;
    km_plant_t p;
    assert_false(km_plant_init(&p, NULL));
    km_plant_config_t c = km_plant_default_config;
    c.motor_r_mohm = 0;
    assert_false(km_plant_init(&p, &c));
    c = km_plant_default_config;
    c.substep_us = 0;
    assert_false(km_plant_init(&p, &c));
    c = km_plant_default_config;
    c.gear_eff_pct = 101;
    assert_false(km_plant_init(&p, &c));
    c = km_plant_default_config;
    c.supply_r_mohm = (uint16_t)(c.motor_r_mohm * 5);
    assert_false(km_plant_init(&p, &c));
    /* a tiny inertia forces a shorter sub-step, and stays stable */
    c = km_plant_default_config;
    c.rotor_j_gmm2 = 1;
    c.load_j_gmm2 = 0;
    assert_true(km_plant_init(&p, &c));
    assert_true(p.sub_us < c.substep_us);
    km_plant_input_t in = drive(1000);
    run_ms(&p, &in, 1000);
    assert_true(km_plant_at_endstop(&p));
    assert_int_equal(km_plant_speed_mdps(&p), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_at_rest_nothing_moves),
        cmocka_unit_test(test_small_pwm_held_by_friction),
        cmocka_unit_test(test_full_pwm_reaches_no_load_speed_both_signs),
        cmocka_unit_test(test_half_pwm_half_speed),
        cmocka_unit_test(test_brake_stops_faster_than_coast),
        cmocka_unit_test(test_endstop_stalls_at_v_over_r),
        cmocka_unit_test(test_voltage_sags_under_load),
        cmocka_unit_test(test_temperature_rises_under_stall_and_relaxes),
        cmocka_unit_test(test_external_torque),
        cmocka_unit_test(test_long_runs_no_overflow),
        cmocka_unit_test(test_deterministic_and_dt_independent),
        cmocka_unit_test(test_faults),
        cmocka_unit_test(test_encoder_counts_within_one_turn),
        cmocka_unit_test(test_physics_survive_a_restart),
        cmocka_unit_test(test_init_rejects_bad_config),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
