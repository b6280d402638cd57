/* SPDX-License-Identifier: Apache-2.0 */
/* Servo mode (docs/protocol.md §5.4): the torque switch 0x64 (0 free,
 * 1 brake, 2 on, 3 armed, 5 protecting) and the rotation commands
 * 0x65..0x68 as profile moves; targets clamped to the travel, 0x19/0x1A
 * and one move's span; status bit 7, 0x4D and 0x4C. The rules:
 * docs/control-design.md "Servo mode". */
#ifndef KM_SERVO_MODE_H
#define KM_SERVO_MODE_H

#include <stdbool.h>
#include <stdint.h>

#include "km_output.h"
#include "km_profile.h"
#include "km_params.h"
#include "km_request.h"

#define KM_STREAM_GAP_US 200000u /* a 0x68 later than this after the previous one starts a new stream */

typedef struct {
    uint8_t ts;   /* km_torque_t as control runs it */
    bool touched; /* a torque command has come since power-on */
    /* the byte flags first: an M0 byte access reaches 32 bytes into a struct */
    bool running;    /* status bit 7 */
    bool streaming;  /* the last move was a stream target */
    bool reset_loop; /* the loop starts afresh at the next tick */
    km_profile_t profile;
    int32_t target;       /* 0.1 deg, the target in force */
    int32_t pwm_cap;      /* this move's own PWM bound, else 1000 */
    uint32_t rotation_ms; /* 0x4D */
    uint32_t rotation_rem_us;
    uint32_t settle_us; /* since the profile reached the target and the shaft last moved */
    int32_t settle_pos; /* where the shaft was when that clock (re)started, 0.1 deg */
    uint32_t stream_us; /* since the last stream target */
} km_servo_mode_t;

typedef struct {
    km_bridge_mode_t bridge; /* PWM = the position loop drives */
    int32_t setpoint_u;      /* profile set-point, 0.001 x 0.1 deg from profile.origin */
    int32_t setpoint_ddps;   /* profile speed, 0.1 deg/s */
    int32_t pwm_cap;         /* the move's own PWM bound */
    bool reset_loop;         /* clear the loop's integrator first */
    bool holding;            /* the set-point is at rest on the target */
} km_servo_mode_out_t;

void km_servo_mode_init(km_servo_mode_t *m, const km_control_params_t *p);

/* The torque switch set at measured `position`. False when refused: ON
 * while protecting, or PROTECTED (km_servo_mode_protect's). */
bool km_servo_mode_torque(km_servo_mode_t *m, km_torque_t torque, int32_t position);

/* A move at measured `position`. False when torque off or protecting. */
bool km_servo_mode_move(km_servo_mode_t *m, const km_move_t *mv, const km_control_params_t *p,
                        int32_t position);

/* Arrived (bit 7 clears): profile done, shaft slower than SPEED and inside
 * the arrive band less MARGIN (a reading's error, issue 20 criterion 6). */
#define KM_ARRIVE_SPEED_DDPS 200
#define KM_ARRIVE_MARGIN_DDEG 1

/* One tick: advances the profile and the running state. */
void km_servo_mode_step(km_servo_mode_t *m, const km_control_params_t *p, int32_t position,
                        int32_t speed_ddps, uint32_t dt_us, km_servo_mode_out_t *out);

/* Target and profile restart from `position` (0x64 keeps its value). */
void km_servo_mode_rebase(km_servo_mode_t *m, int32_t position);

/* Hook for the protection supervisor: 0x64 = 5, motion stops, output free. */
void km_servo_mode_protect(km_servo_mode_t *m);

/* Deviation (0x4C): position - target while on, else 0. */
int32_t km_servo_mode_deviation(const km_servo_mode_t *m, int32_t position);

/* Clamps a target to the travel (the pot product's) and the angle limits (0 = none). */
int32_t km_servo_mode_clamp(const km_control_params_t *p, int32_t target);

#endif
