/* SPDX-License-Identifier: Apache-2.0 */
/* Product configuration of an STM32G031 servo: the calibration constants
 * that turn ADC counts into engineering units. One const instance per
 * product (board_config.c); factory calibration may later override it. */
#ifndef BOARD_CONFIG_H
#define BOARD_CONFIG_H

#include <stdint.h>

#define KM_NTC_POINTS 20u

typedef struct {
    /* Potentiometer: raw counts (12 bit) at -135.0° and at +135.0°. Either
     * order; a reversed pot just swaps them. */
    uint16_t pot_raw_min;
    uint16_t pot_raw_max;
    /* Readings this close to a rail mean a broken wiper or supply. */
    uint16_t rail_margin;
    /* ADC reference (VDDA) in mV. */
    uint16_t vref_mv;
    /* Current: shunt in milliohm and amplifier gain; the amplifier output at
     * zero current in raw counts. */
    uint16_t shunt_mohm;
    uint16_t shunt_gain;
    uint16_t shunt_offset_raw;
    /* Supply divider (top + bottom) / bottom as a fraction. */
    uint16_t vdiv_num;
    uint16_t vdiv_den;
    /* NTC divider: raw counts at -40, -30 ... +150 °C (falling). */
    uint16_t ntc_raw[KM_NTC_POINTS];
    int16_t ntc_first_c10; /* temperature of ntc_raw[0], 0.1 °C */
    int16_t ntc_step_c10;  /* spacing of the table, 0.1 °C */
} km_board_config_t;

extern const km_board_config_t km_board_config;

#endif
