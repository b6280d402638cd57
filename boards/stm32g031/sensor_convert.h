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

#endif
