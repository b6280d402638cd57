/* SPDX-License-Identifier: Apache-2.0 */
/* The realistic plant (sim/plant/km_plant_real.c, docs/plant.md): each test
 * checks one physical behaviour against the parameters of
 * km_plant_realistic_params (not against numbers read back from the
 * model), so a wrong equation, unit or sign fails. Doubles are fine here:
 * the host computes the expected physics, the plant is fixed-point. */
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

static km_plant_config_t s_cfg; /* the plant keeps a pointer to its config */
static km_plant_real_t s_real;

/* The realistic config with its own realism copy, to vary; `free` = no pot,
 * no end stops (the encoder product's shaft). */
static km_plant_config_t *real_config(bool free_shaft)
{
    s_real = km_plant_realistic_params;
    s_cfg = km_plant_realistic_config;
    s_cfg.real = &s_real;
    if (free_shaft) {
        s_cfg.pot_travel_ddeg = 0;
        s_cfg.endstop_ddeg = 0;
    }
    return &s_cfg;
}

/* Steps the plant for ms 1 ms ticks with one input. */
static void run_ms(km_plant_t *p, const km_plant_input_t *in, uint32_t ms)
{
    for (uint32_t i = 0; i < ms; i++) {
        km_plant_step(p, in, 1000);
    }
}

/* Back-EMF constant at the output, V per rad/s (= N·m per A). */
static double ke_out(void) /* V per rad/s at the output = N·m per A at the output */
{
    return s_cfg.motor_ke_uv_s_rad * 1e-6 * s_cfg.gear_ratio;
}

/* Both configurations by name; the ideal one is the default, unchanged. */
static void test_named_configurations(void **state)
{
    (void)state;
    assert_ptr_equal(km_plant_config_named("ideal"), &km_plant_default_config);
    assert_ptr_equal(km_plant_config_named("realistic"), &km_plant_realistic_config);
    assert_null(km_plant_config_named("Realistic"));
    assert_null(km_plant_config_named(""));
    assert_null(km_plant_config_named(NULL));
    assert_null(km_plant_default_config.real);
    assert_ptr_equal(km_plant_realistic_config.real, &km_plant_realistic_params);
    km_plant_t p;
    assert_true(km_plant_init(&p, &km_plant_realistic_config));
}

/* The same seed and inputs give the same readings bit for bit; another
 * seed gives other noise. */
static void test_noise_is_reproducible(void **state)
{
    (void)state;
    km_plant_t a, b;
    km_plant_config_t *c = real_config(false);
    assert_true(km_plant_init(&a, c));
    assert_true(km_plant_init(&b, c));
    unsigned same_as_other_seed = 0;
    km_plant_t o;
    static km_plant_config_t c2;
    static km_plant_real_t r2;
    r2 = s_real;
    r2.seed = 99u;
    c2 = *c;
    c2.real = &r2;
    assert_true(km_plant_init(&o, &c2));
    for (int i = 0; i < 3000; i++) {
        const km_plant_input_t in = {KM_PLANT_DRIVE, (int16_t)((i / 300) % 2 ? 200 : -200), 0};
        km_plant_step(&a, &in, 1000);
        km_plant_step(&b, &in, 1000);
        km_plant_step(&o, &in, 1000);
        assert_int_equal(km_plant_position_ddeg(&a), km_plant_position_ddeg(&b));
        assert_int_equal(km_plant_pot_adc(&a), km_plant_pot_adc(&b));
        assert_int_equal(km_plant_encoder_counts(&a), km_plant_encoder_counts(&b));
        assert_int_equal(km_plant_current_ma(&a), km_plant_current_ma(&b));
        same_as_other_seed += km_plant_pot_adc(&a) == km_plant_pot_adc(&o) ? 1u : 0u;
    }
    assert_true(same_as_other_seed < 2500u);
}

/* The pot through the ADC: at rest the reading is centred on the true
 * angle; its spread is the per-sample noise over sqrt(16) plus the final
 * rounding; the position is the board's conversion of the ADC value. */
static void test_pot_reading_noise_and_quantisation(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(false);
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    km_plant_set_position_ddeg(&p, 437);
    const double want_adc = (437.0 + c->pot_travel_ddeg) * 4095.0 / (2.0 * c->pot_travel_ddeg);
    double s1 = 0, s2 = 0;
    const int n = 20000;
    for (int i = 0; i < n; i++) {
        run_ms(&p, &k_coast, 1);
        const double a = km_plant_pot_adc(&p);
        s1 += a;
        s2 += a * a;
        const int32_t want_pos =
            (int32_t)((km_plant_pot_adc(&p) * 2 * c->pot_travel_ddeg + 2047) / 4095) - c->pot_travel_ddeg;
        assert_int_equal(km_plant_position_ddeg(&p), want_pos);
    }
    const double mean = s1 / n;
    const double sd = sqrt(s2 / n - mean * mean);
    const double sigma = s_real.pot_noise_mlsb / 1000.0 / sqrt(1 << s_real.pot_oversample_log2);
    const double want_sd = sqrt(sigma * sigma + 1.0 / 12.0);
    print_message("pot at 43.7 deg: ADC mean %.3f (true %.3f), sd %.3f (expected ~%.3f)\n", mean, want_adc,
                  sd, want_sd);
    assert_true(fabs(mean - want_adc) < 0.1);
    assert_true(sd > 0.8 * want_sd && sd < 1.25 * want_sd);
    assert_int_equal(km_plant_turns_ddeg(&p), 437); /* the shaft itself did not move */
}

/* Without noise the pot reads the true angle to the ADC's resolution, and
 * a moving shaft reads where it was half a sampling window ago. */
static void test_pot_without_noise_and_its_lag(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(false);
    s_real.pot_noise_mlsb = 0;
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    for (int32_t pos = -1300; pos <= 1300; pos += 37) {
        km_plant_set_position_ddeg(&p, pos);
        const double lsb = 2.0 * c->pot_travel_ddeg / 4095.0; /* 0.1° per LSB */
        assert_true(fabs((double)km_plant_position_ddeg(&p) - pos) <= lsb / 2 + 0.5 + 1e-9);
    }
    km_plant_set_position_ddeg(&p, -1000);
    const km_plant_input_t full = {KM_PLANT_DRIVE, 1000, 0};
    run_ms(&p, &full, 300); /* at full speed: the reading sweeps through every ADC code */
    double behind = 0.0;
    const int n = 200;
    for (int i = 0; i < n; i++) {
        run_ms(&p, &full, 1);
        behind += (double)km_plant_shaft_udeg(&p) / 1e5 - km_plant_position_ddeg(&p);
    }
    behind /= n;
    const double speed_ddps = km_plant_speed_mdps(&p) / 100.0;
    const double lag = speed_ddps * s_real.pot_window_us / 2 * 1e-6; /* 0.1° */
    print_message("at %.0f deg/s the pot reads %.2f x 0.1 deg behind the shaft on average (%.2f expected)\n",
                  speed_ddps / 10, behind, lag);
    assert_true(lag > 0.5);
    assert_true(fabs(behind - lag) < 0.25);
}

/* The encoder: counts of the angle within one turn, with noise of
 * enc_noise_mcount plus the rounding to a count; multi-turn reads wrap. */
static void test_encoder_noise_and_wrap(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(true);
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    km_plant_set_position_ddeg(&p, 3600 * 7 + 1234);
    const double want = 1234.0 * 4096.0 / 3600.0;
    double s1 = 0, s2 = 0;
    const int n = 20000;
    for (int i = 0; i < n; i++) {
        run_ms(&p, &k_coast, 1);
        const double v = km_plant_encoder_counts(&p);
        s1 += v;
        s2 += v * v;
    }
    const double mean = s1 / n, sd = sqrt(s2 / n - mean * mean);
    const double sigma = s_real.enc_noise_mcount / 1000.0;
    print_message("encoder: mean %.3f counts (true %.3f), sd %.3f\n", mean, want, sd);
    assert_true(fabs(mean - want) < 0.05);
    assert_true(sd > 0.8 * sqrt(sigma * sigma + 1.0 / 12) && sd < 1.25 * sqrt(sigma * sigma + 1.0 / 12));
    km_plant_set_position_ddeg(&p, -3600 * 3 - 1); /* just below a whole turn, negative */
    assert_true(km_plant_encoder_counts(&p) >= 4093u || km_plant_encoder_counts(&p) <= 1u);
}

/* Full PWM: no-load speed set by the back-EMF; stall current V / R_total
 * with the shared bus (the servo's lead plus bus_servos x the shared
 * source). */
static void test_speed_and_shared_supply(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(true);
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    const km_plant_input_t full = {KM_PLANT_DRIVE, 1000, 0};
    run_ms(&p, &full, 1500);
    const double ideal_dps = c->supply_mv / 1000.0 / ke_out() * 180.0 / PI;
    const double dps = km_plant_speed_mdps(&p) / 1000.0;
    assert_true(dps > 0.93 * ideal_dps && dps < ideal_dps);
    for (uint8_t n = 1; n <= 4; n += 3) {
        c = real_config(false);
        s_real.bus_servos = n;
        assert_true(km_plant_init(&p, c));
        km_plant_set_position_ddeg(&p, c->endstop_ddeg);
        run_ms(&p, &full, 100);
        const double r_src = c->supply_r_mohm + n * s_real.bus_r_mohm; /* mΩ */
        const double i = km_plant_current_ma(&p);
        const double sag = c->supply_mv - km_plant_voltage_mv(&p);
        print_message("%u servos on the bus: stall %.0f mA, sag %.0f mV (%.0f mΩ expected)\n", n, i, sag,
                      r_src);
        assert_true(fabs(sag / i * 1000.0 - r_src) < 0.02 * r_src + 3);
        assert_true(fabs(i - c->supply_mv * 1000.0 / (c->motor_r_mohm + r_src)) < 0.02 * i);
    }
}

/* The bridge: an on-pulse shorter than the minimum does not switch, a
 * longer one loses the dead time; near 100 % the bridge stays on. */
static void test_bridge_minimum_pulse_and_dead_time(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(false);
    km_plant_t p;
    const int32_t min_pm = (int32_t)s_real.min_pulse_ns * 1000 / s_real.pwm_period_ns;
    const int32_t dead_pm = (int32_t)s_real.dead_ns * 1000 / s_real.pwm_period_ns;
    assert_true(min_pm > 0 && dead_pm > 0);
    assert_true(km_plant_init(&p, c));
    km_plant_set_position_ddeg(&p, c->endstop_ddeg); /* blocked: current = V d / R */
    const km_plant_input_t short_on = {KM_PLANT_DRIVE, (int16_t)(min_pm - 1), 0};
    run_ms(&p, &short_on, 5);
    assert_int_equal(km_plant_current_ma(&p), 0);
    const km_plant_input_t on = {KM_PLANT_DRIVE, 100, 0};
    run_ms(&p, &on, 300); /* the motor side takes up the play and stops against the gears */
    const double want = (100 - dead_pm) / 1000.0 * km_plant_voltage_mv(&p) / c->motor_r_mohm * 1000.0;
    assert_true(fabs(km_plant_current_ma(&p) - want) < 0.02 * want + 2);
    const km_plant_input_t near_full = {KM_PLANT_DRIVE, (int16_t)(1000 - min_pm + 1), 0};
    run_ms(&p, &near_full, 300);
    const int32_t i_near = km_plant_current_ma(&p);
    const km_plant_input_t full = {KM_PLANT_DRIVE, 1000, 0};
    run_ms(&p, &full, 1);
    assert_int_equal(i_near, km_plant_current_ma(&p));
}

/* Hot copper: at +100 °C the copper part of the resistance is 39.3 %
 * higher, and the stall current falls accordingly. */
static void test_winding_resistance_rises_with_temperature(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(false);
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    km_plant_set_position_ddeg(&p, c->endstop_ddeg);
    const km_plant_input_t full = {KM_PLANT_DRIVE, 1000, 0};
    run_ms(&p, &full, 300); /* stalled against the stop, the motor side at rest */
    km_plant_set_temp_dc(&p, c->ambient_dc + 1000);
    run_ms(&p, &full, 2);
    const double r_hot = c->motor_r_mohm + s_real.winding_r_mohm * s_real.tempco_ppm * 1e-6 * 100.0;
    const double want = km_plant_voltage_mv(&p) / r_hot * 1000.0;
    print_message("stall at +100 degC: %d mA (%.0f expected with %.0f mΩ)\n", km_plant_current_ma(&p), want,
                  r_hot);
    assert_true(fabs(km_plant_current_ma(&p) - want) < 0.01 * want + 2);
}

/* Forward efficiency and Stribeck: full PWM lifts at most
 * eff * (Kt I - Tc - Ts) - Tout of opposing torque (the mesh loses
 * (1/eff - 1) of what it carries, the shaft breaks away from rest). */
static void test_lifting_torque_follows_forward_efficiency(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(true);
    km_plant_t p;
    const double eff = c->gear_eff_pct / 100.0;
    const double r_total =
        c->motor_r_mohm + c->supply_r_mohm + s_real.bus_servos * s_real.bus_r_mohm; /* mΩ */
    const double tm = ke_out() * c->supply_mv / r_total;                            /* N·m at stall */
    const double t_max =
        eff * (tm - (c->coulomb_unm + s_real.stribeck_unm) * 1e-6) - s_real.out_coulomb_unm * 1e-6;
    int32_t moved[2];
    for (int k = 0; k < 2; k++) {
        const int32_t t_test = (int32_t)(t_max * 1e6 * (k == 0 ? 0.96 : 1.04));
        assert_true(km_plant_init(&p, c));
        const km_plant_input_t in = {KM_PLANT_DRIVE, 1000, -t_test};
        run_ms(&p, &in, 500);
        moved[k] = km_plant_turns_ddeg(&p);
        print_message("opposing %.3f N.m (limit %.3f): shaft at %.1f deg\n", t_test / 1e6, t_max,
                      moved[k] / 10.0);
    }
    const int32_t lifts = moved[0], fails = moved[1];
    assert_true(lifts > 20); /* 4 % below the limit it turns */
    assert_true(fails < 5);  /* 4 % above it does not (it only takes up the play) */
}

/* Stribeck: while turning, the friction the motor overcomes is
 * Tc + Ts exp(-(w/ws)^2) + viscous + what the output side's own friction
 * costs through the mesh; steady at a speed near ws it is well above the
 * Coulomb level, far above ws it is back to it. A strong excess (100 mN·m,
 * ws 5 °/s) makes the shape stand out of the current's resolution. */
static void test_stribeck_friction_while_turning(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(true);
    s_real.stribeck_unm = 100000;
    s_real.stribeck_ddps = 50;
    const double ws = 5.0, kt = ke_out(); /* °/s, N·m per A */
    const double mu_f = (100.0 - c->gear_eff_pct) / c->gear_eff_pct;
    unsigned near = 0, far = 0;
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    /* from fast down to a stop, slowly: the shaft follows the turning branch */
    for (int16_t pwm = 300; pwm >= 20; pwm = (int16_t)(pwm > 100 ? pwm - 100 : pwm - 1)) {
        const km_plant_input_t in = {KM_PLANT_DRIVE, pwm, 0};
        run_ms(&p, &in, 800);
        const double w = km_plant_speed_mdps(&p) / 1000.0; /* °/s */
        const double friction = kt * km_plant_current_ma(&p) * 1e3 - c->viscous_unm_per_dps * w -
                                (1.0 + mu_f) * s_real.out_coulomb_unm; /* µN·m */
        const double want = c->coulomb_unm + s_real.stribeck_unm * exp(-(w / ws) * (w / ws));
        if (w > 1.4 * ws && w < 1.8 * ws) {
            print_message("PWM %d: %.2f deg/s, friction %.1f mN.m (%.1f expected)\n", pwm, w, friction / 1000,
                          want / 1000);
            assert_true(fabs(friction - want) < 2000.0);
            assert_true(friction > c->coulomb_unm + 0.04 * s_real.stribeck_unm);
            near++;
        } else if (w > 10 * ws) {
            assert_true(fabs(friction - c->coulomb_unm) < 2000.0);
            far++;
        }
    }
    assert_true(near > 0u && far > 0u);
}

/* Back-driving: with the bridge open, a slowly rising torque on the output
 * turns the shaft once it exceeds Tout + (Tc + Ts) / eff_back. */
static void test_back_driving_needs_the_backward_efficiency(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(true);
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    const double want =
        s_real.out_coulomb_unm + (c->coulomb_unm + s_real.stribeck_unm) / (s_real.eff_back_pct / 100.0);
    int32_t t = 0;
    int32_t moved_at = -1;
    for (int ms = 0; ms < 12000 && moved_at < 0; ms++) {
        t = (int32_t)(ms * want * 1.5 / 12000.0); /* a ramp to 1.5x the threshold in 12 s */
        const km_plant_input_t in = {KM_PLANT_COAST, 0, t};
        km_plant_step(&p, &in, 1000);
        if (km_plant_turns_ddeg(&p) >= 4) { /* past half the play and the deflection: the gears turn */
            moved_at = t;
        }
    }
    print_message("back-driven at %.1f mN.m (expected %.1f)\n", moved_at / 1000.0, want / 1000.0);
    assert_true(moved_at > 0);
    assert_true(fabs(moved_at - want) < 0.04 * want);
}

/* Backlash and compliance: with the motor side held by friction, a small
 * torque moves the output across the play and deflects the gears by T/k. */
static void test_backlash_and_stiffness(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(true);
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    const int32_t t = 40000; /* above the output's own friction, below back-driving */
    const km_plant_input_t plus = {KM_PLANT_COAST, 0, t};
    const km_plant_input_t minus = {KM_PLANT_COAST, 0, -t};
    run_ms(&p, &plus, 300);
    const int64_t a = km_plant_shaft_udeg(&p);
    run_ms(&p, &minus, 300);
    const int64_t b = km_plant_shaft_udeg(&p);
    const double k_per_deg = s_real.stiff_unm_per_mdeg * 1000.0; /* µN·m per ° */
    const double net = t - (double)s_real.out_coulomb_unm;       /* what the gears carry */
    const double want = s_real.backlash_mdeg / 1000.0 + 2.0 * net / k_per_deg;
    const double span = (double)(a - b) / 1e6;
    /* the output's own stiction lets it stop anywhere within +-Tout of the balance */
    const double tol = 2.0 * s_real.out_coulomb_unm / k_per_deg + 0.001;
    print_message("play + deflection: %.4f deg (expected %.4f +- %.4f)\n", span, want, tol);
    assert_true(fabs(span - want) < tol);
}

/* Gravity: an arm held horizontal falls toward hanging down when the
 * bridge lets go, and stops where gravity no longer beats the gears'
 * back-driving friction. */
static void test_gravity_pulls_the_arm_down(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(true);
    s_real.gravity_unm = 500000;     /* 0.5 N·m arm */
    s_real.gravity_down_ddeg = -900; /* hangs down at -90° */
    km_plant_t p;
    assert_true(km_plant_init(&p, c));
    run_ms(&p, &k_coast, 3000);
    const double pos = km_plant_turns_ddeg(&p) / 10.0;
    const double hold =
        s_real.out_coulomb_unm + (c->coulomb_unm + s_real.stribeck_unm) / (s_real.eff_back_pct / 100.0);
    const double band = asin(hold / s_real.gravity_unm) * 180.0 / PI;
    print_message("arm from horizontal: rests at %.1f deg (down at -90, friction band %.1f deg)\n", pos,
                  band);
    assert_true(pos < -90.0 + band + 1.0 && pos > -90.0 - band - 1.0);
    assert_int_equal(km_plant_speed_mdps(&p), 0);
}

/* A restart keeps the realistic shaft where it was (gears relaxed). */
static void test_physics_survive_a_restart(void **state)
{
    (void)state;
    km_plant_config_t *c = real_config(true);
    km_plant_t p, q;
    assert_true(km_plant_init(&p, c));
    const km_plant_input_t in = {KM_PLANT_DRIVE, 600, 0};
    run_ms(&p, &in, 700);
    run_ms(&p, &k_coast, 2000);
    km_plant_physics_t ph;
    km_plant_get_physics(&p, &ph);
    assert_true(km_plant_init(&q, c));
    km_plant_set_physics(&q, &ph);
    assert_int_equal(km_plant_turns_ddeg(&q), km_plant_turns_ddeg(&p));
    assert_true(abs(km_plant_encoder_counts(&q) - km_plant_encoder_counts(&p)) <= 3);
    assert_int_equal(km_plant_time_ms(&q), km_plant_time_ms(&p));
}

/* Parameters the integer model cannot run are refused. */
static void test_init_rejects_bad_realism(void **state)
{
    (void)state;
    km_plant_t p;
    km_plant_config_t *c = real_config(false);
    s_real.stiff_unm_per_mdeg = 0;
    assert_false(km_plant_init(&p, c));
    c = real_config(false);
    s_real.bus_servos = 0;
    assert_false(km_plant_init(&p, c));
    c = real_config(false);
    s_real.pwm_period_ns = 0;
    assert_false(km_plant_init(&p, c));
    c = real_config(false);
    s_real.winding_r_mohm = c->motor_r_mohm;
    assert_false(km_plant_init(&p, c));
    c = real_config(false);
    s_real.bus_r_mohm = c->motor_r_mohm;
    assert_false(km_plant_init(&p, c));
    c = real_config(false);
    c->load_j_gmm2 = 10;
    assert_false(km_plant_init(&p, c));
    c = real_config(false);
    assert_true(km_plant_init(&p, c));
}

/* The realistic plant's tests. */
int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_named_configurations),
        cmocka_unit_test(test_noise_is_reproducible),
        cmocka_unit_test(test_pot_reading_noise_and_quantisation),
        cmocka_unit_test(test_pot_without_noise_and_its_lag),
        cmocka_unit_test(test_encoder_noise_and_wrap),
        cmocka_unit_test(test_speed_and_shared_supply),
        cmocka_unit_test(test_bridge_minimum_pulse_and_dead_time),
        cmocka_unit_test(test_winding_resistance_rises_with_temperature),
        cmocka_unit_test(test_lifting_torque_follows_forward_efficiency),
        cmocka_unit_test(test_stribeck_friction_while_turning),
        cmocka_unit_test(test_back_driving_needs_the_backward_efficiency),
        cmocka_unit_test(test_backlash_and_stiffness),
        cmocka_unit_test(test_gravity_pulls_the_arm_down),
        cmocka_unit_test(test_physics_survive_a_restart),
        cmocka_unit_test(test_init_rejects_bad_realism),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
