/* SPDX-License-Identifier: Apache-2.0 */
/* Default calibration: 270° pot, 50 mΩ shunt x 20 (1 V/A), 100k/10k divider,
 * 10 kΩ B3950 NTC under 10 kΩ to VDDA. */
#include "board_config.h"

#include "sensor_convert.h"

#define PRV_POT_MIN 205u /* 5 % of range */
#define PRV_POT_MAX 3890u
#define PRV_VREF_MV 3300u
#define PRV_SHUNT_MOHM 50u
#define PRV_SHUNT_GAIN 20u
#define PRV_SHUNT_OFFSET 0u
#define PRV_VDIV_NUM 11u
#define PRV_VDIV_DEN 1u
/* raw = 4095 * R(T) / (R(T) + 10k), R(T) = 10k * exp(3950 (1/T - 1/298.15)) */
#define PRV_NTC_0 3996u
#define PRV_NTC_1 3900u
#define PRV_NTC_2 3740u
#define PRV_NTC_3 3495u
#define PRV_NTC_4 3156u
#define PRV_NTC_5 2738u
#define PRV_NTC_6 2278u
#define PRV_NTC_7 1825u
#define PRV_NTC_8 1419u
#define PRV_NTC_9 1081u
#define PRV_NTC_10 815u
#define PRV_NTC_11 613u
#define PRV_NTC_12 462u
#define PRV_NTC_13 350u
#define PRV_NTC_14 267u
#define PRV_NTC_15 206u
#define PRV_NTC_16 160u
#define PRV_NTC_17 126u
#define PRV_NTC_18 100u
#define PRV_NTC_19 80u
#define PRV_NTC_FIRST_C10 (-400)
#define PRV_NTC_STEP_C10 100

const km_board_config_t km_board_config = {
    .pot_raw_min = PRV_POT_MIN,
    .pot_raw_max = PRV_POT_MAX,
    .rail_margin = 16u,
    .vref_mv = PRV_VREF_MV,
    .shunt_mohm = PRV_SHUNT_MOHM,
    .shunt_gain = PRV_SHUNT_GAIN,
    .shunt_offset_raw = PRV_SHUNT_OFFSET,
    .vdiv_num = PRV_VDIV_NUM,
    .vdiv_den = PRV_VDIV_DEN,
    .ntc_raw = {PRV_NTC_0,  PRV_NTC_1,  PRV_NTC_2,  PRV_NTC_3,  PRV_NTC_4,  PRV_NTC_5,  PRV_NTC_6,
                PRV_NTC_7,  PRV_NTC_8,  PRV_NTC_9,  PRV_NTC_10, PRV_NTC_11, PRV_NTC_12, PRV_NTC_13,
                PRV_NTC_14, PRV_NTC_15, PRV_NTC_16, PRV_NTC_17, PRV_NTC_18, PRV_NTC_19},
    .ntc_first_c10 = PRV_NTC_FIRST_C10,
    .ntc_step_c10 = PRV_NTC_STEP_C10,
};

/* km_conv_prepare's prv_ratio as constant expressions (sensor_convert.c):
 * q_k = num * 2^k / den; the shift is the number of steps k < 30 with
 * q_k * 2 + 1 <= limit (q_k grows with k, so the loop stops at the first
 * that fails); the multiplier q_shift, plus 1 when the remainder is at
 * least half den and q + 1 stays within the limit. den 0 is {0, 0}. */
#define PRV_DEN(den) ((uint64_t)((den) ? (den) : 1u))
#define PRV_Q(num, den, k) (((uint64_t)(num) << (k)) / PRV_DEN(den))
#define PRV_LIMIT(max_x) (0x7FFFFFFFu / (max_x))
#define PRV_STEP(num, den, lim, k) (PRV_Q(num, den, k) * 2u + 1u <= (lim) ? 1u : 0u)
#define PRV_STEPS4(n, d, l, k)                                                            \
    (PRV_STEP(n, d, l, (k)) + PRV_STEP(n, d, l, (k) + 1u) + PRV_STEP(n, d, l, (k) + 2u) + \
     PRV_STEP(n, d, l, (k) + 3u))
#define PRV_SHIFT_L(n, d, l)                                                          \
    (PRV_STEPS4(n, d, l, 0u) + PRV_STEPS4(n, d, l, 4u) + PRV_STEPS4(n, d, l, 8u) +    \
     PRV_STEPS4(n, d, l, 12u) + PRV_STEPS4(n, d, l, 16u) + PRV_STEPS4(n, d, l, 20u) + \
     PRV_STEPS4(n, d, l, 24u) + PRV_STEP(n, d, l, 28u) + PRV_STEP(n, d, l, 29u))
#define PRV_SHIFT(n, d, max_x) PRV_SHIFT_L(n, d, PRV_LIMIT(max_x))
#define PRV_QS(n, d, max_x) PRV_Q(n, d, PRV_SHIFT(n, d, max_x))
#define PRV_REM(n, d, max_x) (((uint64_t)(n) << PRV_SHIFT(n, d, max_x)) % PRV_DEN(d))
#define PRV_MUL(n, d, max_x)                                                                            \
    ((d) == 0u ? 0u                                                                                     \
               : (uint32_t)(PRV_QS(n, d, max_x) + (PRV_REM(n, d, max_x) * 2u >= (d) &&                  \
                                                           PRV_QS(n, d, max_x) + 1u <= PRV_LIMIT(max_x) \
                                                       ? 1u                                             \
                                                       : 0u)))
#define PRV_RATIO(n, d, max_x)                                                  \
    {                                                                           \
        PRV_MUL(n, d, max_x), (d) == 0u ? 0u : (uint32_t)PRV_SHIFT(n, d, max_x) \
    }

/* The position line (prv_prepare_position): the ratio for twice the ADC's
 * range, signed as the span, half a unit and the start folded into the base. */
#define PRV_SPAN ((int32_t)PRV_POT_MAX - (int32_t)PRV_POT_MIN)
#define PRV_SPAN_ABS ((uint32_t)(PRV_SPAN < 0 ? -PRV_SPAN : PRV_SPAN))
#define PRV_POT_SHIFT (PRV_SPAN == 0 ? 0u : (uint32_t)PRV_SHIFT(2700u, PRV_SPAN_ABS, 2u * KM_ADC_FULL_SCALE))
#define PRV_POT_MUL_ABS ((int32_t)PRV_MUL(2700u, PRV_SPAN_ABS, 2u * KM_ADC_FULL_SCALE))
#define PRV_POT_MUL (PRV_SPAN == 0 ? 0 : PRV_SPAN < 0 ? -PRV_POT_MUL_ABS : PRV_POT_MUL_ABS)
#define PRV_POT_HALF (PRV_POT_SHIFT ? (int32_t)(1u << (PRV_POT_SHIFT - 1u)) : 0)
#define PRV_POT_BASE (PRV_SPAN == 0 ? 1350 : PRV_POT_HALF - (int32_t)PRV_POT_MIN * PRV_POT_MUL)

/* The current's and the supply voltage's ratios (km_conv_prepare). */
#define PRV_CURRENT_NUM ((uint32_t)(PRV_VREF_MV * 1000u))
#define PRV_CURRENT_DEN ((uint32_t)(KM_ADC_FULL_SCALE * PRV_SHUNT_MOHM * PRV_SHUNT_GAIN))
#define PRV_VOLTAGE_NUM ((uint32_t)(PRV_VREF_MV * PRV_VDIV_NUM))
#define PRV_VOLTAGE_DEN ((uint32_t)(KM_ADC_FULL_SCALE * PRV_VDIV_DEN))

/* One NTC segment's multiplier: step / (raw[i-1] - raw[i]) << 16, rounded. */
#define PRV_NTC_STEP \
    ((uint32_t)(PRV_NTC_STEP_C10 < 0 ? -PRV_NTC_STEP_C10 : PRV_NTC_STEP_C10) << KM_CONV_NTC_SHIFT)
#define PRV_NTC_MUL(hi, lo) ((hi) - (lo) ? (PRV_NTC_STEP + ((hi) - (lo)) / 2u) / ((hi) - (lo)) : 0u)

const km_conv_t km_board_conv = {
    .pot_mul = PRV_POT_MUL,
    .pot_base = PRV_POT_BASE,
    .pot_shift = PRV_POT_SHIFT,
    .shunt_offset = PRV_SHUNT_OFFSET,
    .current = PRV_RATIO(PRV_CURRENT_NUM, PRV_CURRENT_DEN, KM_ADC_FULL_SCALE),
    .voltage = PRV_RATIO(PRV_VOLTAGE_NUM, PRV_VOLTAGE_DEN, KM_ADC_FULL_SCALE),
    .ntc_mul = {0u,
                PRV_NTC_MUL(PRV_NTC_0, PRV_NTC_1),
                PRV_NTC_MUL(PRV_NTC_1, PRV_NTC_2),
                PRV_NTC_MUL(PRV_NTC_2, PRV_NTC_3),
                PRV_NTC_MUL(PRV_NTC_3, PRV_NTC_4),
                PRV_NTC_MUL(PRV_NTC_4, PRV_NTC_5),
                PRV_NTC_MUL(PRV_NTC_5, PRV_NTC_6),
                PRV_NTC_MUL(PRV_NTC_6, PRV_NTC_7),
                PRV_NTC_MUL(PRV_NTC_7, PRV_NTC_8),
                PRV_NTC_MUL(PRV_NTC_8, PRV_NTC_9),
                PRV_NTC_MUL(PRV_NTC_9, PRV_NTC_10),
                PRV_NTC_MUL(PRV_NTC_10, PRV_NTC_11),
                PRV_NTC_MUL(PRV_NTC_11, PRV_NTC_12),
                PRV_NTC_MUL(PRV_NTC_12, PRV_NTC_13),
                PRV_NTC_MUL(PRV_NTC_13, PRV_NTC_14),
                PRV_NTC_MUL(PRV_NTC_14, PRV_NTC_15),
                PRV_NTC_MUL(PRV_NTC_15, PRV_NTC_16),
                PRV_NTC_MUL(PRV_NTC_16, PRV_NTC_17),
                PRV_NTC_MUL(PRV_NTC_17, PRV_NTC_18),
                PRV_NTC_MUL(PRV_NTC_18, PRV_NTC_19)},
};
