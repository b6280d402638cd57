/* SPDX-License-Identifier: Apache-2.0 */
/* What the dispatcher asks of control, decoded (docs/protocol.md §4, §6). */
#ifndef KM_REQUEST_H
#define KM_REQUEST_H

#include <stdbool.h>
#include <stdint.h>

/* Motor mode (docs/protocol.md §5.4: 0x6E, 0x6F, 0x70, 0x5A = 2), built
 * unless a board leaves it out with KM_FEATURE_MOTOR_MODE=0 (the 32 KiB
 * STM32G031F6 build, docs/footprint.md "What gives way"). */
#ifndef KM_FEATURE_MOTOR_MODE
#define KM_FEATURE_MOTOR_MODE 1
#endif

/* Servo mode's torque switch, numbered as 0x64 reads it. */
typedef enum {
    KM_TORQUE_FREE = 0,      /* off, output free */
    KM_TORQUE_BRAKE = 1,     /* off, output braked */
    KM_TORQUE_ON = 2,        /* holds, or follows the last move */
    KM_TORQUE_ARMED = 3,     /* off; on at the next move */
    KM_TORQUE_PROTECTED = 5, /* a protection acts (never a request) */
} km_torque_t;

typedef enum {
    KM_MOVE_TIME,   /* in `time_or_speed` ms */
    KM_MOVE_SPEED,  /* at `time_or_speed` deg/s, cut to the limit */
    KM_MOVE_STREAM, /* a stream's target, at its rate */
} km_move_kind_t;

typedef struct {
    uint8_t kind;           /* km_move_kind_t */
    bool relative;          /* adds to the target in force */
    int16_t target;         /* 0.1 deg, the master's frame */
    uint16_t time_or_speed; /* 0 = fastest */
    uint16_t pwm_cap;       /* this move's bound, PWM (1000 = none) */
} km_move_t;

/* Motor mode: a constant output or speed. */
typedef enum {
    KM_RUN_PWM,   /* `value`: PWM */
    KM_RUN_SPEED, /* `value`: deg/s */
    KM_RUN_STOP,  /* now, output `after` */
} km_run_mode_t;

/* When a run ends by itself. */
typedef enum {
    KM_UNTIL_NONE,  /* runs on */
    KM_UNTIL_TIME,  /* `amount` x 0.1 s */
    KM_UNTIL_ANGLE, /* `amount` deg */
    KM_UNTIL_TURNS, /* `amount` x 0.1 turn */
} km_run_until_t;

/* The output once a run has stopped. */
typedef enum {
    KM_AFTER_IDLE, /* 0x11 bit 1 */
    KM_AFTER_FREE,
    KM_AFTER_BRAKE,
} km_run_after_t;

typedef struct {
    uint8_t mode;    /* km_run_mode_t */
    bool reverse;    /* negative in the master's frame */
    uint16_t value;  /* magnitude */
    uint8_t until;   /* km_run_until_t */
    uint16_t amount; /* of `until`; 0 with a bound ends at once */
    uint8_t after;   /* km_run_after_t */
} km_motor_run_t;

typedef enum {
    KM_REQ_TORQUE, /* .torque, not PROTECTED */
    KM_REQ_MOVE,
    KM_REQ_MOTOR,
    KM_REQ_ZERO_POSITION,    /* the position now is zero */
    KM_REQ_PROTECTION_CLEAR, /* .clear: KM_PROT_* bits */
} km_request_kind_t;

/* Word-aligned: built, zeroed and copied as three words, not by newlib's
 * byte loops (docs/benchmarks.md "Lists"). */
typedef struct {
    _Alignas(4) uint8_t kind; /* km_request_kind_t */
    union {
        uint8_t torque;
        km_move_t move;
        km_motor_run_t run;
        uint8_t clear;
    } u;
} km_request_t;

/* Less motion: never refused (docs/protocol-decisions.md "Protections"). */
static inline bool km_request_less_motion(const km_request_t *r)
{
    switch (r->kind) {
    case KM_REQ_TORQUE:
        return r->u.torque <= KM_TORQUE_BRAKE;
    case KM_REQ_MOTOR:
        return r->u.run.mode == KM_RUN_STOP || r->u.run.value == 0u ||
               (r->u.run.until != KM_UNTIL_NONE && r->u.run.amount == 0u);
    default:
        return false;
    }
}

#endif
