/* SPDX-License-Identifier: Apache-2.0 */
/* Calibration constants from ADC counts to units; one per product (board_config.c). */
#ifndef BOARD_CONFIG_H
#define BOARD_CONFIG_H

#include <stdint.h>

#define KM_NTC_POINTS 20u

typedef struct {
    /* Pot raw counts at -135.0° and +135.0° (either order). */
    uint16_t pot_raw_min;
    uint16_t pot_raw_max;
    /* Readings this close to a rail are a fault. */
    uint16_t rail_margin;
    /* VDDA, mV. */
    uint16_t vref_mv;
    /* Shunt mΩ, amplifier gain, zero-current raw reading. */
    uint16_t shunt_mohm;
    uint16_t shunt_gain;
    uint16_t shunt_offset_raw;
    /* Supply divider (top + bottom) / bottom. */
    uint16_t vdiv_num;
    uint16_t vdiv_den;
    /* NTC raw counts at -40, -30 ... +150 °C. */
    uint16_t ntc_raw[KM_NTC_POINTS];
    int16_t ntc_first_c10; /* 0.1 °C */
    int16_t ntc_step_c10;  /* 0.1 °C */
} km_board_config_t;

extern const km_board_config_t km_board_config;

#endif
