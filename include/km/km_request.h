/* What the dispatcher asks of control: a typed request (motion, torque
 * switch, zeroing, protection clear). Control answers accepted or refused;
 * the dispatcher sets status bit 6 on a refusal (PROTOCOL.md §4, §6).
 * Shared by protocol/ and control/; a leaf header. */
#ifndef KM_REQUEST_H
#define KM_REQUEST_H

#include <stdbool.h>
#include <stdint.h>

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

#endif
