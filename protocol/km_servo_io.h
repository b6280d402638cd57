/* The servo <-> control seam (../shared/DESIGN.md "The servo <-> control
 * seam"): the only types the dispatcher (protocol/km_servo.c) and control
 * (control/) share. A leaf header: it includes nothing of either side.
 *
 *  - km_request_t: a typed request from the dispatcher to control (motion,
 *    torque switch, zeroing, protection clear). Control answers accepted or
 *    refused; the dispatcher sets status bit 6 on a refusal (§4, §6).
 *  - km_control_params_t: the control registers decoded into engineering
 *    units by the dispatcher (km_servo_control_params()), re-decoded by the
 *    app only when km_servo_params_gen() says a register changed.
 *  - km_live_t: what control reports back every tick (§5.3 live registers,
 *    status bit 7, protections, the 0x64 = 5 hook). */
#ifndef KM_SERVO_IO_H
#define KM_SERVO_IO_H

#include <stdbool.h>
#include <stdint.h>

#include "km_product.h"

/* Typed requests to control (motion, torque, zeroing, protection). */
typedef enum {
    KM_REQ_TORQUE_SWITCH,   /* .u8 = new 0x64 value (0, 1, 2, 3) */
    KM_REQ_MOVE_TIME,       /* .move: target 0.1 deg, param ms (0 = fastest) */
    KM_REQ_MOVE_SPEED,      /* .move: target 0.1 deg, param deg/s (0 = fastest) */
    KM_REQ_SERVO_ADVANCED,  /* .adv: control byte, p1, p2 (§5.4 0x67) */
    KM_REQ_INTERPOLATE,     /* .move.target */
    KM_REQ_MOTOR_TORQUE,    /* .i16 PWM -1000..1000 */
    KM_REQ_MOTOR_SPEED,     /* .i16 deg/s */
    KM_REQ_MOTOR_ADVANCED,  /* .adv: control byte, p1, p2 (§5.4 0x70) */
    KM_REQ_ZERO_POSITION,   /* make the current position zero (0x46 write, 0x18 = 0 on encoders) */
    KM_REQ_PROTECTION_CLEAR,/* .u8 = mask of protections to release (0x36) */
} km_request_kind_t;

typedef struct {
    km_request_kind_t kind;
    union {
        uint8_t u8;
        int16_t i16;
        struct {
            int16_t target;
            uint16_t param;
        } move;
        struct {
            uint8_t control;
            uint16_t p1;  /* as sent: an i16 for 0x67, a u16 for 0x70 */
            uint16_t p2;
        } adv;
    } u;
} km_request_t;

/* A request for less motion: one that only stops the shaft or lets it go
 * (0x64 = 0/1; 0x6E = 0; 0x6F = 0; 0x70 with its stop bit 7, or with
 * nothing to run: a PWM or speed of 0, or a counted run of 0). Never
 * refused for a protection acting or a hardware fault latched
 * (docs/protocol-decisions.md "Protections"). */
static inline bool km_request_less_motion(const km_request_t *r)
{
    switch (r->kind) {
    case KM_REQ_TORQUE_SWITCH:
        return r->u.u8 <= 1u;
    case KM_REQ_MOTOR_TORQUE:
    case KM_REQ_MOTOR_SPEED:
        return r->u.i16 == 0;
    case KM_REQ_MOTOR_ADVANCED:
        return (r->u.adv.control & 0x80u) != 0u || r->u.adv.p2 == 0u ||
               ((r->u.adv.control & 0x30u) != 0u && r->u.adv.p1 == 0u);
    default:
        return false;
    }
}

/* Control registers in engineering units. Angles are 0.1 deg in the frame
 * the master sees (zero offsets and direction applied), like 0x46. */
typedef struct {
    km_variant_t variant;        /* §6 product variant */
    bool reverse;                /* 0x11 bit 2: counter-clockwise positive */
    bool idle_brake;             /* 0x11 bit 1: idle output brake damping (else free) */
    bool power_on_brake;         /* 0x11 bit 0: power-on output brake damping */
    int16_t zero_offset1;        /* 0x16, 0.1 deg */
    int16_t zero_offset2;        /* 0x17, 0.1 deg */
    uint16_t max_torque;         /* 0x13, PWM 0..1000 */
    uint16_t max_current_ma;     /* 0x14 */
    uint16_t max_speed_dps;      /* 0x15 */
    int16_t angle_min;           /* 0x19, 0.1 deg, 0 = no limit */
    int16_t angle_max;           /* 0x1A, 0.1 deg, 0 = no limit */
    int16_t travel_min;          /* product travel: targets never go outside it */
    int16_t travel_max;
    int16_t pos_read_min;        /* the readings a sound position sensor gives (km_product.h) */
    int16_t pos_read_max;
    uint8_t prot_enable;         /* 0x32 bits: 3 stall, 2 temperature, 1 current, 0 voltage */
    uint8_t prot_release;        /* 0x33 same bits: 1 = released only by command */
    uint8_t prot_state;          /* 0x34: 2 bits per protection */
    uint8_t voltage_high_v;      /* 0x3C */
    uint8_t voltage_low_v;
    uint8_t temp_trip_c;         /* 0x3D */
    uint8_t temp_hysteresis_c;
    uint16_t current_trip_ma;    /* 0x3E */
    uint8_t current_time_100ms;
    uint16_t stall_pwm;          /* 0x3F */
    uint8_t stall_time_100ms;
    uint8_t control_mode;        /* 0x5A: 0 auto, 1 servo only, 2 motor only */
    uint16_t torque_limit;       /* 0x5B, PWM 0..1000 (<= 0x13) */
    uint16_t current_limit_ma;   /* 0x5C (<= 0x14) */
    uint16_t speed_limit_dps;    /* 0x5D (<= 0x15) */
    uint8_t torque_switch;       /* 0x64 */
    km_control_gains_t gains;    /* the product's loop gains (km_product.h) */
} km_control_params_t;

/* Live state from control, copied in every control tick. */
typedef struct {
    int32_t position;      /* 0.1 deg, zero offsets applied */
    int32_t speed;         /* deg/s */
    int32_t current;       /* mA */
    int32_t pwm;           /* 0..1000 */
    int32_t temperature;   /* deg C */
    int32_t voltage;       /* mV */
    int32_t deviation;     /* 0.1 deg */
    uint32_t rotation_ms;  /* 0x4D */
    bool running;          /* status bit 7 */
    bool protecting;       /* a protection acts on the output: 0x64 reads 5 */
    uint8_t torque_switch; /* 0x64 as control runs it; after a release, what 0x64 returns to */
    uint8_t protections;   /* active protections, 0x36 bits / status bits 0..3 */
    uint8_t hw_faults;     /* 0x35 bits found by the self-test (latched) */
    uint32_t time_ms;      /* ms since control started: the fault log's clock */
} km_live_t;

#endif
