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

/* num/den as (mul, shift) with max_x * mul < 2^31, the longest shift that
 * allows, by long division one bit at a time (one 32-bit division, at
 * preparation only). */
static km_conv_ratio_t prv_ratio(uint32_t num, uint32_t den, uint32_t max_x)
{
    km_conv_ratio_t r = {0u, 0u};
    if (den == 0u) {
        return r;
    }
    uint32_t q = num / den;
    uint32_t rem = num % den;
    const uint32_t limit = 0x7FFFFFFFu / (max_x ? max_x : 1u);
    while (r.shift < 30u && q * 2u + 1u <= limit) {
        rem *= 2u;
        q *= 2u;
        if (rem >= den) {
            rem -= den;
            q++;
        }
        r.shift++;
    }
    /* Rounded to nearest: the last bit's remainder decides. */
    if (rem * 2u >= den && q + 1u <= limit) {
        q++;
    }
    r.mul = q;
    return r;
}

/* The position line as one multiply, add and shift: x = raw - pot_min (the
 * other way for a reversed pot) times mul, plus half a unit, floored; within
 * 1 of km_conv_position (half a unit below the travel's start rounds up, not
 * away from zero). The ratio is made for twice the ADC's range, so |x| * mul
 * and raw_min * mul stay below 2^30, half a unit below 2^29: no sum overflows. */
static void prv_prepare_position(const km_board_config_t *cfg, km_conv_t *conv)
{
    const int32_t span = (int32_t)cfg->pot_raw_max - (int32_t)cfg->pot_raw_min;
    if (span == 0) {
        conv->pot_mul = 0;
        conv->pot_base = 1350; /* position 0 */
        conv->pot_shift = 0u;
        return;
    }
    const km_conv_ratio_t r = prv_ratio(2700u, (uint32_t)(span < 0 ? -span : span), 2u * KM_ADC_FULL_SCALE);
    const int32_t mul = span < 0 ? -(int32_t)r.mul : (int32_t)r.mul;
    const int32_t half = r.shift ? (int32_t)(1u << (r.shift - 1u)) : 0;
    conv->pot_mul = mul;
    conv->pot_base = half - (int32_t)cfg->pot_raw_min * mul;
    conv->pot_shift = r.shift;
}

void km_conv_prepare(const km_board_config_t *cfg, km_conv_t *conv)
{
    prv_prepare_position(cfg, conv);
    conv->shunt_offset = cfg->shunt_offset_raw;
    /* I[mA] = raw * vref / 4095 * 1000 / (R * gain) */
    const uint32_t div = (uint32_t)cfg->shunt_mohm * cfg->shunt_gain;
    conv->current = div ? prv_ratio(cfg->vref_mv * 1000u, KM_ADC_FULL_SCALE * div, KM_ADC_FULL_SCALE)
                        : (km_conv_ratio_t){0u, 0u};
    conv->voltage = cfg->vdiv_den ? prv_ratio((uint32_t)cfg->vref_mv * cfg->vdiv_num,
                                              KM_ADC_FULL_SCALE * cfg->vdiv_den, KM_ADC_FULL_SCALE)
                                  : (km_conv_ratio_t){0u, 0u};
    conv->ntc_mul[0] = 0u;
    for (uint32_t i = 1u; i < KM_NTC_POINTS; i++) {
        /* into <= seg, so into * mul <= step << 16 whatever the segment */
        const uint32_t seg = (uint32_t)cfg->ntc_raw[i - 1u] - cfg->ntc_raw[i];
        const int32_t c10 = cfg->ntc_step_c10;
        const uint32_t step = (uint32_t)(c10 < 0 ? -c10 : c10) << KM_CONV_NTC_SHIFT;
        conv->ntc_mul[i] = seg ? (step + seg / 2u) / seg : 0u;
    }
}

int32_t km_conv_fast_position(const km_conv_t *conv, uint16_t raw)
{
    return (((int32_t)raw * conv->pot_mul + conv->pot_base) >> conv->pot_shift) - 1350;
}

int32_t km_conv_fast_current_ma(const km_conv_t *conv, uint16_t raw)
{
    const int32_t net = (int32_t)raw - (int32_t)conv->shunt_offset;
    return net <= 0 ? 0 : (int32_t)((uint32_t)net * conv->current.mul >> conv->current.shift);
}

int32_t km_conv_fast_voltage_mv(const km_conv_t *conv, uint16_t raw)
{
    return (int32_t)((uint32_t)raw * conv->voltage.mul >> conv->voltage.shift);
}

int32_t km_conv_fast_temperature_c10(const km_board_config_t *cfg, const km_conv_t *conv, uint8_t *ntc_at,
                                     uint16_t raw)
{
    const uint16_t *t = cfg->ntc_raw;
    if (raw >= t[0]) {
        return cfg->ntc_first_c10;
    }
    /* The first i >= 1 with raw >= t[i] (the table falls), walked to from
     * the last reading's segment rather than from 1 (from 0 the first time:
     * raw < t[0] here, so the walk passes to 1). */
    uint32_t i = *ntc_at;
    while (i > 1u && raw >= t[i - 1u]) {
        i--;
    }
    while (i < KM_NTC_POINTS && raw < t[i]) {
        i++;
    }
    if (i == KM_NTC_POINTS) {
        return cfg->ntc_first_c10 + (int32_t)(KM_NTC_POINTS - 1u) * cfg->ntc_step_c10;
    }
    *ntc_at = (uint8_t)i;
    const int32_t lo_c = cfg->ntc_first_c10 + (int32_t)(i - 1u) * cfg->ntc_step_c10;
    const uint32_t into = (uint32_t)t[i - 1u] - raw;
    const int32_t q =
        (int32_t)((into * conv->ntc_mul[i] + (1u << (KM_CONV_NTC_SHIFT - 1u))) >> KM_CONV_NTC_SHIFT);
    return lo_c + (cfg->ntc_step_c10 < 0 ? -q : q);
}
