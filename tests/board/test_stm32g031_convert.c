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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_position_ends_and_middle),
        cmocka_unit_test(test_position_reversed_pot),
        cmocka_unit_test(test_current_voltage),
        cmocka_unit_test(test_ntc_table_and_interpolation),
        cmocka_unit_test(test_rails),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
