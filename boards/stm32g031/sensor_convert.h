/* SPDX-License-Identifier: Apache-2.0 */
/* ADC counts -> engineering units for the STM32G031 board, in integer fixed
 * point (no FPU on the M0+). Pure functions of a config and raw 12-bit
 * counts, so they can be tested on the host. */
#ifndef SENSOR_CONVERT_H
#define SENSOR_CONVERT_H

#include <stdbool.h>
#include <stdint.h>

#include "board_config.h"

#define KM_ADC_FULL_SCALE 4095u

/* Register 0x35 sensor fault bits. */
#define KM_FAULT_POSITION (1u << 5)
#define KM_FAULT_CURRENT (1u << 4)
#define KM_FAULT_VOLTAGE (1u << 3)
#define KM_FAULT_TEMPERATURE (1u << 2)

/* 0.1° of the output shaft, -1350..1350 across the calibrated travel
 * (extrapolated beyond it). */
int32_t km_conv_position(const km_board_config_t *cfg, uint16_t raw);

/* Current magnitude in mA (the caller signs it with the drive direction). */
int32_t km_conv_current_ma(const km_board_config_t *cfg, uint16_t raw);

int32_t km_conv_voltage_mv(const km_board_config_t *cfg, uint16_t raw);

/* 0.1 °C by linear interpolation in the NTC table; clamped to its ends. */
int32_t km_conv_temperature_c10(const km_board_config_t *cfg, uint16_t raw);

/* True when the reading sits within rail_margin of 0 or full scale. */
bool km_conv_at_rail(const km_board_config_t *cfg, uint16_t raw);

/* A ratio num/den as a multiplier and a shift: x * num / den is
 * (x * mul) >> shift for every x up to the max_x it was made for. */
typedef struct {
    uint32_t mul;
    uint32_t shift;
} km_conv_ratio_t;

/* The conversions above with every division done once, here: per reading
 * they are multiplies and shifts (on the M0+ a 32-bit division is a
 * library call, __aeabi_idiv / __aeabi_uidiv, and these run every control
 * tick). Each result is within 1 of the function above (tests/board/
 * test_stm32g031_convert.c checks every raw count). */
#define KM_CONV_NTC_SHIFT 16u

typedef struct {
    /* position = ((raw * pot_mul + pot_base) >> pot_shift) - 1350: the
     * calibration's line, its sign and rounding in the two factors (signed,
     * arithmetic shift); a span of 0 is pot_mul 0, pot_base 1350 */
    int32_t pot_mul;
    int32_t pot_base;
    uint32_t pot_shift;
    uint16_t shunt_offset;
    km_conv_ratio_t current;
    km_conv_ratio_t voltage;
    /* [i]: ntc_step_c10 / (ntc_raw[i-1] - ntc_raw[i]) << KM_CONV_NTC_SHIFT, rounded */
    uint32_t ntc_mul[KM_NTC_POINTS];
} km_conv_t;

void km_conv_prepare(const km_board_config_t *cfg, km_conv_t *conv);

/* km_conv_prepare(&km_board_config) done by the compiler (board_config.c):
 * the firmware converts with it and links no preparation code. */
extern const km_conv_t km_board_conv;
int32_t km_conv_fast_position(const km_conv_t *conv, uint16_t raw);
int32_t km_conv_fast_current_ma(const km_conv_t *conv, uint16_t raw);
int32_t km_conv_fast_voltage_mv(const km_conv_t *conv, uint16_t raw);
/* *ntc_at: the NTC segment the last reading fell in (1..KM_NTC_POINTS-1; 0
 * before the first), where the search starts, the temperature moving
 * slowly; kept up to date here. The result does not depend on it. */
int32_t km_conv_fast_temperature_c10(const km_board_config_t *cfg, const km_conv_t *conv, uint8_t *ntc_at,
                                     uint16_t raw);

#endif
