/* SPDX-License-Identifier: Apache-2.0 */
/* Fixed-point sensor conversions (see sensor_convert.h). All products are
 * bounded well inside 32 bits: raw <= 4095, factors <= 65535. */
#include "sensor_convert.h"

bool km_conv_at_rail(const km_board_config_t *cfg, uint16_t raw)
{
    return raw <= cfg->rail_margin || raw >= KM_ADC_FULL_SCALE - cfg->rail_margin;
}

int32_t km_conv_position(const km_board_config_t *cfg, uint16_t raw)
{
    int32_t span = (int32_t)cfg->pot_raw_max - (int32_t)cfg->pot_raw_min;
    if (span == 0) {
        return 0;
    }
    int32_t num = ((int32_t)raw - (int32_t)cfg->pot_raw_min) * 2700;
    if (span < 0) { /* reversed pot: same line, both signs flipped */
        span = -span;
        num = -num;
    }
    /* Division rounded to nearest, symmetric about zero. */
    int32_t q = num >= 0 ? (num + span / 2) / span : (num - span / 2) / span;
    return q - 1350;
}

static int32_t prv_adc_mv(const km_board_config_t *cfg, uint16_t raw)
{
    return (int32_t)(((uint32_t)raw * cfg->vref_mv + KM_ADC_FULL_SCALE / 2u) / KM_ADC_FULL_SCALE);
}

int32_t km_conv_current_ma(const km_board_config_t *cfg, uint16_t raw)
{
    int32_t net = (int32_t)raw - (int32_t)cfg->shunt_offset_raw;
    if (net < 0) {
        net = 0;
    }
    /* I[mA] = V[mV] * 1000 / (R[mΩ] * gain) */
    int32_t mv = prv_adc_mv(cfg, (uint16_t)net);
    int32_t div = (int32_t)cfg->shunt_mohm * (int32_t)cfg->shunt_gain;
    return div > 0 ? mv * 1000 / div : 0;
}

int32_t km_conv_voltage_mv(const km_board_config_t *cfg, uint16_t raw)
{
    if (cfg->vdiv_den == 0u) {
        return 0;
    }
    return prv_adc_mv(cfg, raw) * (int32_t)cfg->vdiv_num / (int32_t)cfg->vdiv_den;
}

int32_t km_conv_temperature_c10(const km_board_config_t *cfg, uint16_t raw)
{
    const uint16_t *t = cfg->ntc_raw;
    if (raw >= t[0]) {
        return cfg->ntc_first_c10;
    }
    for (uint32_t i = 1u; i < KM_NTC_POINTS; i++) {
        if (raw >= t[i]) {
            /* t[i-1] > raw >= t[i]: interpolate between the two points. */
            int32_t lo_c = cfg->ntc_first_c10 + (int32_t)(i - 1u) * cfg->ntc_step_c10;
            int32_t span = (int32_t)t[i - 1u] - (int32_t)t[i];
            int32_t into = (int32_t)t[i - 1u] - (int32_t)raw;
            return lo_c + (into * cfg->ntc_step_c10 + span / 2) / span;
        }
    }
    return cfg->ntc_first_c10 + (int32_t)(KM_NTC_POINTS - 1u) * cfg->ntc_step_c10;
}
