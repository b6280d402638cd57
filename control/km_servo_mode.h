/* SPDX-License-Identifier: Apache-2.0 */
/* Servo mode (docs/protocol.md §5.4): the torque switch 0x64 as a state machine
 * and the rotation commands 0x65..0x68 turned into profile moves.
 *
 *  0x64 = 0  off, free: motion stops, bridge free.
 *  0x64 = 1  off, brake damping: motion stops, bridge brake.
 *  0x64 = 2  on: holds the position it had when switched on, or the
 *            target of the last rotation command.
 *  0x64 = 3  armed: off now (the idle output of 0x11 bit 1; before any
 *            torque command, the power-on output of 0x11 bit 0); the next
 *            rotation command turns it on (2) from the current position.
 *  0x64 = 5  protecting: km_servo_mode_protect(), the hook for the
 *            protection supervisor (a later issue): motion stops, free.
 *
 * Targets (0.1 deg, the master's frame) are clamped to the product travel
 * (in the sensor's frame, moved into the master's: km_axis.h; none on the
 * multi-turn encoder product), to the angle limits 0x19/0x1A when they are
 * set (0 = no limit), and to one move's span from the set-point
 * (km_profile_reach: 90,000 deg, reached only after a long motor run). A
 * relative move (km_move_t.relative, 0x67) adds to the target in force (the
 * last one commanded, or the held position), or to the measured position
 * when the torque was off, and the sum is clamped the same way: relative
 * moves never accumulate the tracking error and never pass a limit.
 *
 * Speeds: "fastest" (omitted or 0 parameter) = the speed limit 0x5D (or the
 * product's fastest_dps when 0x5D is 0; never above fastest_dps), at the
 * product acceleration; a
 * requested speed above 0x5D is cut to it; a move in time whose speed would
 * exceed 0x5D takes longer; a move's own PWM cap (0x67) bounds the output
 * until the next move. A stream of targets (KM_MOVE_STREAM, 0x68): the
 * first one (or one more than KM_STREAM_GAP_US after the previous) is a
 * fastest move;
 * each later one is reached at constant speed over 5/4 of the time since
 * the previous one (km_profile.h), so the shaft runs about an interval
 * behind the master without stopping at each target.
 *
 * Running (status bit 7) and rotation time (0x4D) start at each accepted
 * rotation command. The motion ends when the profile is at the target and
 * the shaft is within the product's arrive_ddeg of it, or once the shaft
 * has stayed within arrive_ddeg of one place for settle_ms after the
 * profile got there (a blocked shaft; a shaft still creeping toward the
 * target restarts that clock): bit 7 clears and 0x4D stops.
 * Switching the torque off (0, 1) or protecting ends it at once.
 * Deviation (0x4C) = measured position - target, 0 with the torque off. */
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
    km_profile_t profile;
    int32_t target;       /* 0.1 deg, the target in force */
    int32_t pwm_cap;      /* this move's own PWM bound, else 1000 */
    bool running;         /* status bit 7 */
    uint32_t rotation_ms; /* 0x4D */
    uint32_t rotation_rem_us;
    uint32_t settle_us; /* since the profile reached the target and the shaft last moved */
    int32_t settle_pos; /* where the shaft was when that clock (re)started, 0.1 deg */
    bool streaming;     /* the last move was a stream target */
    uint32_t stream_us; /* since the last stream target */
    bool reset_loop;    /* the loop starts afresh at the next tick */
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

/* The torque switch set to `torque` (FREE, BRAKE, ON, ARMED) at measured
 * `position` (0.1 deg). False when refused: ON while protecting, or
 * PROTECTED (only km_servo_mode_protect() sets it). */
bool km_servo_mode_torque(km_servo_mode_t *m, km_torque_t torque, int32_t position);

/* A move at measured `position`. False when refused: torque off or
 * protecting. */
bool km_servo_mode_move(km_servo_mode_t *m, const km_move_t *mv, const km_control_params_t *p,
                        int32_t position);

/* A move has arrived (status bit 7 clears) once the profile is done and
 * the shaft is inside the product's arrive band and slower than this: a
 * shaft passing through the band is still moving (0.1 deg/s). */
#define KM_ARRIVE_SPEED_DDPS 200
/* ... and the reading inside the band by this much (0.1 deg): what the
 * reading can be off the shaft (one ADC step, noise, the oversampling
 * lag), so that a shaft reported arrived is inside the band (issue 20
 * criterion 6). */
#define KM_ARRIVE_MARGIN_DDEG 1

/* One tick: advances the profile and the running state; `speed_ddps` is
 * the measured speed (0.1 deg/s). */
void km_servo_mode_step(km_servo_mode_t *m, const km_control_params_t *p, int32_t position,
                        int32_t speed_ddps, uint32_t dt_us, km_servo_mode_out_t *out);

/* Motor mode handed the shaft back: the target in force and the profile
 * restart from `position` (0x64 keeps its value). */
void km_servo_mode_rebase(km_servo_mode_t *m, int32_t position);

/* Hook for the protection supervisor: 0x64 = 5, motion stops, output free. */
void km_servo_mode_protect(km_servo_mode_t *m);

/* Deviation (0x4C): position - target while on, else 0. */
int32_t km_servo_mode_deviation(const km_servo_mode_t *m, int32_t position);

/* Clamps a target to the travel (the pot product's) and the angle limits (0 = none). */
int32_t km_servo_mode_clamp(const km_control_params_t *p, int32_t target);

#endif
