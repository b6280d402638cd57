/* SPDX-License-Identifier: Apache-2.0 */
/* What differs between servo models (docs/protocol.md §6). */
#ifndef KM_PRODUCT_H
#define KM_PRODUCT_H

#include <stdint.h>

typedef enum {
    KM_VARIANT_POTENTIOMETER = 0, /* limited travel, absolute position */
    KM_VARIANT_ENCODER = 1,       /* multi-turn, speed control, zeroing */
} km_variant_t;

/* Loop gains and profile limits (docs/tuning.md). */
typedef struct {
    uint16_t kp_q8;          /* PWM per 0.1 deg of error, Q8 */
    uint16_t kd_q8;          /* PWM per deg/s of speed error, Q8 */
    uint16_t ki_q8;          /* PWM per 0.1 deg.s, Q8 */
    uint16_t i_max_pwm;      /* integrator bound */
    uint16_t kv_q8;          /* speed feedforward, PWM per deg/s, Q8 */
    uint16_t friction_pwm;   /* friction feedforward */
    uint16_t tau_ms;         /* accel feedforward time constant */
    uint32_t accel_dps2;     /* profile acceleration */
    uint16_t fastest_dps;    /* "fastest" when 0x5D is 0 */
    uint16_t arrive_ddeg;    /* a move ends this close to the target */
    uint16_t settle_ms;      /* ... or this long after the profile got there */
    uint16_t hold_band_ddeg; /* holding dead band */
    uint16_t kp_hold_q8;     /* kp once settled (0 = kp_q8) */
    uint16_t ki_hold_q4;     /* ki once settled, Q4 (0 = ki_q8) */
} km_control_gains_t;

/* Defaults: docs/tuning.md. */
#define KM_CONTROL_GAINS_DEFAULT                                                                          \
    {                                                                                                     \
        .kp_q8 = 2560, .kd_q8 = 768, .ki_q8 = 10240, .i_max_pwm = 1000, .kv_q8 = 700, .friction_pwm = 15, \
        .tau_ms = 28, .accel_dps2 = 4000, .fastest_dps = 360, .arrive_ddeg = 5, .settle_ms = 300,         \
        .hold_band_ddeg = 1, .kp_hold_q8 = 3840, .ki_hold_q4 = 4096,                                      \
    }

typedef struct {
    const char *model;         /* 0x0A, ASCII, <= 16 chars */
    uint32_t firmware_version; /* 0x0C, 0x@@##&&&& */
    km_variant_t variant;
    /* Defaults (§5). */
    uint16_t max_current_ma;       /* 0x14 */
    uint16_t max_speed_dps;        /* 0x15 */
    int16_t zero_offset1;          /* 0x16, factory calibration */
    int16_t angle_min;             /* 0x19, 0 = no limit */
    int16_t angle_max;             /* 0x1A */
    uint8_t voltage_high_v;        /* 0x3C field 1 */
    uint8_t voltage_low_v;         /* 0x3C field 2 */
    uint16_t current_threshold_ma; /* 0x3E field 1 */
    /* Ranges; angles 0.1 deg. */
    uint16_t baud_min_100; /* 0x10, 100 baud units */
    uint16_t baud_max_100;
    uint16_t current_max_ma; /* bound of 0x14, 0x5C, 0x3E */
    uint16_t speed_max_dps;  /* bound of 0x15, 0x5D */
    int16_t travel_min;      /* angle limits and targets */
    int16_t travel_max;
    /* Pots: the readings the mechanics can give (sensor frame). */
    int16_t pos_read_min;
    int16_t pos_read_max;
    int16_t zero_offset2_max;        /* |0x17| bound */
    uint8_t voltage_max_v;           /* bound of 0x3C */
    const km_control_gains_t *gains; /* NULL = KM_CONTROL_GAINS_DEFAULT */
} km_product_t;

/* A variant as the firmware sees it: a board built as one product fixes it
 * with -DKM_PRODUCT_VARIANT=... (its product.c then declares that variant),
 * so the checks for the other variant fold away at compile time; else `v`. */
static inline km_variant_t km_variant_fixed_or(km_variant_t v)
{
#ifdef KM_PRODUCT_VARIANT
    (void)v;
    return KM_PRODUCT_VARIANT;
#else
    return v;
#endif
}

/* The product's variant (§6), fixed where the board fixes it. */
static inline km_variant_t km_product_variant(const km_product_t *product)
{
    return km_variant_fixed_or(product->variant);
}

#endif
