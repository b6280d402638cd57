/* SPDX-License-Identifier: Apache-2.0 */
/* What the dispatcher asks of control, decoded by the registers' hooks (docs/protocol.md §4, §6); a leaf
 * header. */
#ifndef KM_REQUEST_H
#define KM_REQUEST_H

#include <stdbool.h>
#include <stdint.h>

/* The torque switch of servo mode. Numbered as register 0x64 reads it, so
 * the register can show control's state without a table. */
typedef enum {
    KM_TORQUE_FREE = 0,      /* off, output free; motion stops */
    KM_TORQUE_BRAKE = 1,     /* off, output braked; motion stops */
    KM_TORQUE_ON = 2,        /* on: holds, or follows the last move */
    KM_TORQUE_ARMED = 3,     /* off now; on at the next move, from where the shaft is */
    KM_TORQUE_PROTECTED = 5, /* a protection acts on the output (control's, never a request) */
} km_torque_t;

/* How a move reaches its target. */
typedef enum {
    KM_MOVE_TIME,   /* in `time_or_speed` ms; 0 = fastest */
    KM_MOVE_SPEED,  /* at `time_or_speed` deg/s, cut to the speed limit; 0 = fastest */
    KM_MOVE_STREAM, /* one target of a stream, paced by the stream's own rate */
} km_move_kind_t;

typedef struct {
    uint8_t kind;           /* km_move_kind_t */
    bool relative;          /* target adds to the target in force */
    int16_t target;         /* 0.1 deg, the master's frame */
    uint16_t time_or_speed; /* ms (TIME) or deg/s (SPEED); 0 = fastest */
    uint16_t pwm_cap;       /* this move's own output bound, PWM 0..1000 (1000 = none) */
} km_move_t;

/* Motor mode: the shaft turns at a constant output or speed. */
typedef enum {
    KM_RUN_PWM,   /* `value` = PWM 0..1000 */
    KM_RUN_SPEED, /* `value` = deg/s */
    KM_RUN_STOP,  /* stop now, output `after` */
} km_run_mode_t;

/* When a run ends by itself. */
typedef enum {
    KM_UNTIL_NONE,  /* runs on */
    KM_UNTIL_TIME,  /* `amount` x 0.1 s */
    KM_UNTIL_ANGLE, /* `amount` deg of travel */
    KM_UNTIL_TURNS, /* `amount` x 0.1 turn of travel */
} km_run_until_t;

/* The output once a run has stopped. */
typedef enum {
    KM_AFTER_IDLE, /* the idle output (0x11 bit 1) */
    KM_AFTER_FREE,
    KM_AFTER_BRAKE,
} km_run_after_t;

typedef struct {
    uint8_t mode;    /* km_run_mode_t */
    bool reverse;    /* direction: negative in the master's frame */
    uint16_t value;  /* magnitude: PWM or deg/s */
    uint8_t until;   /* km_run_until_t */
    uint16_t amount; /* of `until`; 0 with a bound = a run of nothing, ends at once */
    uint8_t after;   /* km_run_after_t */
} km_motor_run_t;

typedef enum {
    KM_REQ_TORQUE,           /* .torque: a km_torque_t other than PROTECTED */
    KM_REQ_MOVE,             /* .move: servo mode */
    KM_REQ_MOTOR,            /* .run: motor mode */
    KM_REQ_ZERO_POSITION,    /* make the current position zero */
    KM_REQ_PROTECTION_CLEAR, /* .clear: protections to release (KM_PROT_* bits) */
} km_request_kind_t;

typedef struct {
    uint8_t kind; /* km_request_kind_t */
    union {
        uint8_t torque;
        km_move_t move;
        km_motor_run_t run;
        uint8_t clear;
    } u;
} km_request_t;

/* A request for less motion: never refused for a protection or a fault (docs/protocol-decisions.md
 * "Protections"). */
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
