/* SPDX-License-Identifier: Apache-2.0 */
/* Product configuration: what differs between servo models (docs/protocol.md §6).
 * A board fills one of these; the register table takes every product-
 * dependent default and range from it, never from literals. */
#ifndef KM_PRODUCT_H
#define KM_PRODUCT_H

#include <stdint.h>

typedef enum {
    KM_VARIANT_POTENTIOMETER = 0, /* limited travel, absolute position */
    KM_VARIANT_ENCODER = 1,       /* multi-turn, speed control, zeroing */
} km_variant_t;

/* Position-loop gains and profile limits, the product's (control/, docs/tuning.md). */
typedef struct {
    uint16_t kp_q8;          /* PWM per 0.1 deg of position error, Q8 */
    uint16_t kd_q8;          /* PWM per deg/s of speed error (profile - measured), Q8 */
    uint16_t ki_q8;          /* PWM per 0.1 deg.s of integrated error, Q8 */
    uint16_t i_max_pwm;      /* integrator contribution bound, PWM */
    uint16_t kv_q8;          /* speed feedforward, PWM per deg/s, Q8 (1000 / no-load speed) */
    uint16_t friction_pwm;   /* feedforward against Coulomb friction while moving, PWM */
    uint16_t tau_ms;         /* acceleration feedforward: the motor's mechanical time constant, ms */
    uint32_t accel_dps2;     /* profile acceleration of speed moves and "fastest", deg/s^2 */
    uint16_t fastest_dps;    /* "fastest" when 0x5D is 0, deg/s */
    uint16_t arrive_ddeg;    /* a move ends when the shaft is this close to the target, 0.1 deg */
    uint16_t settle_ms;      /* ... or this long after the profile reached it (blocked shaft) */
    uint16_t hold_band_ddeg; /* holding: the position loop's dead band, 0.1 deg (sensor noise) */
    uint16_t kp_hold_q8;     /* kp once settled (0 = kp_q8): stiffness against a load */
    uint16_t ki_hold_q4;     /* ki once settled, PWM per 0.1 deg.s Q4 (0 = ki_q8): a push taken up */
} km_control_gains_t;

/* The defaults, tuned on the simulated plant: docs/tuning.md. */
#define KM_CONTROL_GAINS_DEFAULT                                                                          \
    {                                                                                                     \
        .kp_q8 = 2560, .kd_q8 = 768, .ki_q8 = 10240, .i_max_pwm = 1000, .kv_q8 = 700, .friction_pwm = 15, \
        .tau_ms = 28, .accel_dps2 = 4000, .fastest_dps = 360, .arrive_ddeg = 5, .settle_ms = 300,         \
        .hold_band_ddeg = 1, .kp_hold_q8 = 3840, .ki_hold_q4 = 4096,                                      \
    }

typedef struct {
    const char *model;         /* 0x0A, ASCII, at most 16 characters */
    uint32_t firmware_version; /* 0x0C, 0x@@##&&&& */
    km_variant_t variant;
    /* Defaults of product-dependent registers (§5). */
    uint16_t max_current_ma;       /* 0x14 */
    uint16_t max_speed_dps;        /* 0x15 */
    int16_t zero_offset1;          /* 0x16, factory calibration, 0.1 deg */
    int16_t angle_min;             /* 0x19, 0.1 deg, 0 = no limit */
    int16_t angle_max;             /* 0x1A */
    uint8_t voltage_high_v;        /* 0x3C first field */
    uint8_t voltage_low_v;         /* 0x3C second field */
    uint16_t current_threshold_ma; /* 0x3E first field */
    /* Valid ranges. */
    uint16_t baud_min_100;   /* 0x10 lowest, in units of 100 baud */
    uint16_t baud_max_100;   /* 0x10 highest */
    uint16_t current_max_ma; /* upper bound of 0x14, 0x5C, 0x3E */
    uint16_t speed_max_dps;  /* upper bound of 0x15, 0x5D */
    int16_t travel_min;      /* lowest angle limit / target, 0.1 deg */
    int16_t travel_max;      /* highest angle limit / target, 0.1 deg */
    /* Potentiometer products: the readings the mechanics can give (0.1 deg, sensor frame); unused on
     * encoders. */
    int16_t pos_read_min;
    int16_t pos_read_max;
    int16_t zero_offset2_max;        /* |0x17| bound, 0.1 deg */
    uint8_t voltage_max_v;           /* upper bound of 0x3C fields */
    const km_control_gains_t *gains; /* NULL = KM_CONTROL_GAINS_DEFAULT */
} km_product_t;

#endif
