/* SPDX-License-Identifier: Apache-2.0 */
/* The control registers, in engineering units. */
#ifndef KM_PARAMS_H
#define KM_PARAMS_H

#include <stdbool.h>
#include <stdint.h>

#include "km_product.h"
#include "km_request.h"

/* 0x5A's values. */
typedef enum {
    KM_MODE_AUTO = 0,       /* follows the command */
    KM_MODE_SERVO_ONLY = 1, /* motor commands refused, a run stops */
    KM_MODE_MOTOR_ONLY = 2, /* servo commands refused */
} km_control_mode_t;

/* 0x5A's largest value: 2, or 1 in a build without motor mode (a write of
 * 2 is then out of range, docs/protocol.md §4). */
#define KM_MODE_LAST (KM_FEATURE_MOTOR_MODE ? KM_MODE_MOTOR_ONLY : KM_MODE_SERVO_ONLY)

/* Angles: 0.1 deg in the master's frame, like 0x46. */
typedef struct {
    km_variant_t variant;    /* §6 */
    bool reverse;            /* 0x11 bit 2: CCW positive */
    bool idle_brake;         /* 0x11 bit 1: idle output braked */
    bool power_on_brake;     /* 0x11 bit 0: braked at power-on */
    int16_t zero_offset1;    /* 0x16, 0.1 deg */
    int16_t zero_offset2;    /* 0x17, 0.1 deg */
    uint16_t max_torque;     /* 0x13, PWM */
    uint16_t max_current_ma; /* 0x14 */
    uint16_t max_speed_dps;  /* 0x15 */
    int16_t angle_min;       /* 0x19, 0.1 deg, 0 = no limit */
    int16_t angle_max;       /* 0x1A */
    int16_t travel_min;      /* product travel: bounds targets */
    int16_t travel_max;
    int16_t pos_read_min;
    int16_t pos_read_max;
    uint8_t prot_enable;    /* 0x32, KM_PROT_* bits */
    uint8_t prot_release;   /* 0x33: 1 = released by command */
    uint8_t prot_state;     /* 0x34: 2 bits per protection */
    uint8_t voltage_high_v; /* 0x3C */
    uint8_t voltage_low_v;
    uint8_t temp_trip_c; /* 0x3D */
    uint8_t temp_hysteresis_c;
    uint16_t current_trip_ma; /* 0x3E */
    uint8_t current_time_100ms;
    uint16_t stall_pwm; /* 0x3F */
    uint8_t stall_time_100ms;
    uint8_t control_mode;      /* km_control_mode_t (0x5A) */
    uint16_t torque_limit;     /* 0x5B, PWM (<= 0x13) */
    uint16_t current_limit_ma; /* 0x5C (<= 0x14) */
    uint16_t speed_limit_dps;  /* 0x5D (<= 0x15) */
    uint8_t torque_switch;     /* km_torque_t (0x64) */
    km_control_gains_t gains;
} km_control_params_t;

/* The product's variant (§6) as control/ sees it: fixed where the board
 * fixes it (km_variant_fixed_or), else p's. */
static inline km_variant_t km_params_variant(const km_control_params_t *p)
{
    return km_variant_fixed_or(p->variant);
}

#endif
