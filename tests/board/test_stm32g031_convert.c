/* SPDX-License-Identifier: Apache-2.0 */
/* STM32G031 sensor conversions against hand-computed values from the default
 * product calibration (board_config.c). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "sensor_convert.h"

static const km_board_config_t *cfg = &km_board_config;

static void test_position_ends_and_middle(void **state)
{
    (void)state;
    assert_int_equal(km_conv_position(cfg, cfg->pot_raw_min), -1350);
    assert_int_equal(km_conv_position(cfg, cfg->pot_raw_max), 1350);
    uint16_t mid = (uint16_t)((cfg->pot_raw_min + cfg->pot_raw_max) / 2u);
    int32_t p = km_conv_position(cfg, mid);
    assert_true(p >= -1 && p <= 1);
}

static void test_position_reversed_pot(void **state)
{
    (void)state;
    km_board_config_t rev = *cfg;
    rev.pot_raw_min = cfg->pot_raw_max;
    rev.pot_raw_max = cfg->pot_raw_min;
    assert_int_equal(km_conv_position(&rev, cfg->pot_raw_max), -1350);
    assert_int_equal(km_conv_position(&rev, cfg->pot_raw_min), 1350);
}

static void test_current_voltage(void **state)
{
    (void)state;
    /* 1 V at the ADC = 1 A through 50 mΩ x 20. 1 V = 1241 counts of 3.3 V. */
    int32_t ma = km_conv_current_ma(cfg, 1241u);
    assert_true(ma >= 995 && ma <= 1005);
    assert_int_equal(km_conv_current_ma(cfg, 0u), 0);
    /* 12 V / 11 = 1.091 V = 1354 counts. */
    int32_t mv = km_conv_voltage_mv(cfg, 1354u);
    assert_true(mv >= 11950 && mv <= 12050);
}

static void test_ntc_table_and_interpolation(void **state)
{
    (void)state;
    assert_int_equal(km_conv_temperature_c10(cfg, 3156u), 0);
    assert_int_equal(km_conv_temperature_c10(cfg, 1825u), 300);
    /* Halfway between 20 °C (2278) and 30 °C (1825). */
    int32_t t = km_conv_temperature_c10(cfg, (2278u + 1825u) / 2u);
    assert_true(t >= 249 && t <= 251);
    assert_int_equal(km_conv_temperature_c10(cfg, 4095u), -400);
    assert_int_equal(km_conv_temperature_c10(cfg, 0u), 1500);
}

static void test_rails(void **state)
{
    (void)state;
    assert_true(km_conv_at_rail(cfg, 0u));
    assert_true(km_conv_at_rail(cfg, 4095u));
    assert_false(km_conv_at_rail(cfg, 2048u));
}

/* The prepared conversions (multiplies and shifts, no division per
 * reading) against the exact ones for every raw count: position and
 * temperature within 1 (0.1 deg, 0.1 C) of the rounded exact quotient;
 * current and voltage within 1 of the true value truncated (the exact
 * functions round the ADC millivolts first, so they sit up to half a
 * millivolt times the divider ratio away). */
static void check_fast_against_exact(const km_board_config_t *c)
{
    km_conv_t conv;
    km_conv_prepare(c, &conv);
    for (uint32_t raw = 0; raw <= KM_ADC_FULL_SCALE; raw++) {
        const uint16_t r = (uint16_t)raw;
        const int32_t dp = km_conv_fast_position(&conv, r) - km_conv_position(c, r);
        assert_true(dp >= -1 && dp <= 1);
        uint8_t ntc_at = 0u;
        const int32_t dt = km_conv_fast_temperature_c10(c, &conv, &ntc_at, r) - km_conv_temperature_c10(c, r);
        assert_true(dt >= -1 && dt <= 1);
        const int64_t net = (int64_t)raw - c->shunt_offset_raw;
        const int64_t div = (int64_t)c->shunt_mohm * c->shunt_gain;
        const int64_t ma_true = net <= 0 ? 0 : net * c->vref_mv * 1000 / ((int64_t)KM_ADC_FULL_SCALE * div);
        const int64_t di = km_conv_fast_current_ma(&conv, r) - ma_true;
        assert_true(di >= -1 && di <= 1);
        const int64_t mv_true =
            (int64_t)raw * c->vref_mv * c->vdiv_num / ((int64_t)KM_ADC_FULL_SCALE * c->vdiv_den);
        const int64_t dv = km_conv_fast_voltage_mv(&conv, r) - mv_true;
        assert_true(dv >= -1 && dv <= 1);
    }
}

static void test_prepared_conversions_match(void **state)
{
    (void)state;
    check_fast_against_exact(cfg);
    km_board_config_t other = *cfg;
    other.pot_raw_min = 3700u; /* reversed, a shorter span */
    other.pot_raw_max = 600u;
    other.shunt_mohm = 33u;
    other.shunt_gain = 50u;
    other.shunt_offset_raw = 40u;
    other.vdiv_num = 47u;
    other.vdiv_den = 4u;
    other.vref_mv = 3000u;
    check_fast_against_exact(&other);
    other.pot_raw_min = 1000u;
    other.pot_raw_max = 1200u;  /* a short travel: a large multiplier */
    other.ntc_first_c10 = 1500; /* a table from hot to cold */
    other.ntc_step_c10 = -75;
    check_fast_against_exact(&other);
}

/* A calibration of no span (pot_raw_min == pot_raw_max) reads position 0
 * at every count, as km_conv_position does; a pot whose line runs past
 * both ends of the ADC (a short span from count 0 or 4095, reversed or not)
 * converts within 1 at every count without overflowing. */
static void test_position_no_span_and_extreme_lines(void **state)
{
    (void)state;
    km_board_config_t c = *cfg;
    c.pot_raw_min = 2000u;
    c.pot_raw_max = 2000u;
    km_conv_t conv;
    km_conv_prepare(&c, &conv);
    for (uint32_t raw = 0; raw <= KM_ADC_FULL_SCALE; raw++) {
        assert_int_equal(km_conv_fast_position(&conv, (uint16_t)raw), 0);
    }
    static const uint16_t ends[][2] = {{0u, 4095u},    {4095u, 0u}, {0u, 1u},
                                       {4095u, 4094u}, {0u, 37u},   {4095u, 4000u}};
    for (unsigned k = 0; k < sizeof ends / sizeof ends[0]; k++) {
        c.pot_raw_min = ends[k][0];
        c.pot_raw_max = ends[k][1];
        km_conv_prepare(&c, &conv);
        for (uint32_t raw = 0; raw <= KM_ADC_FULL_SCALE; raw++) {
            const int32_t d =
                km_conv_fast_position(&conv, (uint16_t)raw) - km_conv_position(&c, (uint16_t)raw);
            assert_true(d >= -1 && d <= 1);
        }
    }
}

/* The NTC search starts at the previous reading's segment (ntc_at, 0
 * before the first reading): readings in any order, near and far jumps,
 * convert exactly as a fresh search does, and within 1 of the exact function. */
static void test_ntc_search_any_order(void **state)
{
    (void)state;
    km_conv_t conv;
    km_conv_prepare(cfg, &conv);
    uint8_t ntc_at = 0u;
    uint32_t raw = 0u;
    for (uint32_t k = 0; k < 3u * (KM_ADC_FULL_SCALE + 1u); k++) {
        /* a stride prime to 4096 visits every count, in jumps; every
         * fourth reading a step of one count, as a slow drift does */
        raw =
            (k % 4u == 3u) ? (raw + 1u) % (KM_ADC_FULL_SCALE + 1u) : (raw + 2731u) % (KM_ADC_FULL_SCALE + 1u);
        uint8_t fresh_at = 0u;
        const int32_t got = km_conv_fast_temperature_c10(cfg, &conv, &ntc_at, (uint16_t)raw);
        assert_int_equal(got, km_conv_fast_temperature_c10(cfg, &conv, &fresh_at, (uint16_t)raw));
        const int32_t d = got - km_conv_temperature_c10(cfg, (uint16_t)raw);
        assert_true(d >= -1 && d <= 1);
        assert_true(raw >= cfg->ntc_raw[0] || (ntc_at >= 1u && ntc_at <= KM_NTC_POINTS - 1u));
    }
}

/* The firmware's conversions (km_board_conv, computed by the compiler in
 * board_config.c) are exactly what km_conv_prepare makes of the product's
 * calibration, field by field. */
static void test_board_conv_is_prepared(void **state)
{
    (void)state;
    km_conv_t conv;
    km_conv_prepare(&km_board_config, &conv);
    assert_int_equal(km_board_conv.pot_mul, conv.pot_mul);
    assert_int_equal(km_board_conv.pot_base, conv.pot_base);
    assert_int_equal(km_board_conv.pot_shift, conv.pot_shift);
    assert_int_equal(km_board_conv.shunt_offset, conv.shunt_offset);
    assert_int_equal(km_board_conv.current.mul, conv.current.mul);
    assert_int_equal(km_board_conv.current.shift, conv.current.shift);
    assert_int_equal(km_board_conv.voltage.mul, conv.voltage.mul);
    assert_int_equal(km_board_conv.voltage.shift, conv.voltage.shift);
    for (uint32_t i = 0u; i < KM_NTC_POINTS; i++) {
        assert_int_equal(km_board_conv.ntc_mul[i], conv.ntc_mul[i]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_position_ends_and_middle),
        cmocka_unit_test(test_position_reversed_pot),
        cmocka_unit_test(test_current_voltage),
        cmocka_unit_test(test_ntc_table_and_interpolation),
        cmocka_unit_test(test_rails),
        cmocka_unit_test(test_prepared_conversions_match),
        cmocka_unit_test(test_position_no_span_and_extreme_lines),
        cmocka_unit_test(test_ntc_search_any_order),
        cmocka_unit_test(test_board_conv_is_prepared),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
