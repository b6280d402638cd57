/* SPDX-License-Identifier: Apache-2.0 */
/* Motor mode (docs/protocol.md §5.4 0x6E..0x70): the shaft turns at a constant
 * PWM or at a constant speed instead of holding a position.
 *
 *  0x6E  constant PWM -1000..1000 (sign = direction, 0 = stop), bounded by
 *        0x5B (and 0x13) in the output stage like every bridge command.
 *  0x6F  constant speed deg/s (sign = direction, 0 = stop): a speed loop
 *        on the fast speed estimator (km_speed_est.h): PWM = kv x speed
 *        (feedforward) + friction + kd x speed error + an integrator
 *        (KM_MOTOR_KI_Q8, bounded by i_max); the speed is cut to 0x5D
 *        (0x15 when 0x5D is 0), the PWM to 0x5B.
 *  0x70  advanced: stop now (with the output free or braked), or a run at
 *        a PWM or a speed, on and on or until a time, an angle or a number
 *        of turns of travel from where the request found the shaft, either
 *        direction, then the output free or braked. A run of 0 (time,
 *        angle or turns 0) ends at once. A counted run slows down before
 *        its end (v^2 = 2 x a/2 x distance left, a = the product's
 *        acceleration, at least KM_MOTOR_CREEP_DDPS) so that it stops on
 *        the count instead of coasting past it.
 * Potentiometer products: no run turns past the product travel (in the
 * master's frame, km_axis_travel): a run slows down the same way toward
 * its edge and ends there, with its stop output; a run away from the edge
 * is taken (docs/protocol-decisions.md "Motor mode and the travel").
 * All three arrive decoded as one km_motor_run_t (include/km/km_request.h).
 * A stop by 0x6E/0x6F = 0 leaves the idle output of 0x11 bit 1.
 *
 * Which variant may do what (0x6F, 0x70 angle/turns/speed: encoder only)
 * and the 0x5A = 1/2 preconditions are the dispatcher's (one place each,
 * docs/protocol-decisions.md "Encoder-only commands", "Motion
 * preconditions"); control trusts them. Directions are in the master's
 * frame: the output stage applies 0x11 bit 2 as for servo mode.
 *
 * Running (status bit 7) and 0x4D start at an accepted motor command that
 * turns the motor (nonzero PWM or speed) and stop when it stops (0, bit 7,
 * a counted run ending, the torque switch, a servo command, 0x5A = 1).
 *
 * Hand-over between the modes (km_control.c): in auto mode (0x5A = 0) the
 * mode follows the command. A motor command ends a servo-mode hold or move
 * at once (the motor owns the bridge; 0x64 keeps its value). A servo
 * rotation command (0x64 = 2 or 3) ends the motor: servo mode starts from
 * the measured position, as if just switched on, so relative targets count
 * from where the motor left the shaft. A torque switch write (0..3) also
 * ends the motor (2 then holds where the shaft is). 0x5A = 1 written while
 * the motor runs stops it with the idle output. The protection supervisor
 * (a later issue) must stop the motor too: km_motor_mode_stop(free). Pure fixed point: no
 * float, no 64-bit divide. */
#ifndef KM_MOTOR_MODE_H
#define KM_MOTOR_MODE_H

#include <stdbool.h>
#include <stdint.h>

#include "km_axis.h"
#include "km_output.h"
#include "km_params.h"
#include "km_request.h"

#define KM_MOTOR_KI_Q8 5120          /* speed loop integrator: PWM per deg of speed error x s, Q8 (20) */
#define KM_MOTOR_CREEP_DDPS 50       /* the slowest approach to a run's end, 0.1 deg/s (5 deg/s) */
#define KM_MOTOR_ROOM_FREE INT32_MAX /* no end ahead of the run */
#define KM_MOTOR_LAG_MS 40           /* the speed loop's lag, taken off the room an approach plans with */

typedef struct {
    bool active;                  /* motor mode owns the bridge */
    bool running;                 /* status bit 7 */
    bool speed_mode;              /* speed loop, else constant PWM */
    int32_t pwm;                  /* constant PWM, master's frame */
    int32_t speed_dps;            /* speed set-point, master's frame */
    uint8_t count_kind;           /* km_run_until_t of the run */
    uint32_t remain_ms;           /* time left (kind 1), ms */
    int32_t start_pos;            /* 0.1 deg, kinds 2/3 */
    int32_t travel;               /* 0.1 deg to go, kinds 2/3 */
    km_bridge_mode_t stop_bridge; /* output once stopped */
    int32_t i_acc;                /* speed integrator, PWM x 256000 */
    uint32_t rotation_ms;         /* 0x4D */
    uint32_t rotation_rem_us;
} km_motor_mode_t;

void km_motor_mode_init(km_motor_mode_t *m);

/* A motor run (0x6E, 0x6F, 0x70) at measured `position`: takes the bridge. */
void km_motor_mode_run(km_motor_mode_t *m, const km_motor_run_t *run, const km_control_params_t *p,
                       int32_t position);

/* Ends motor mode (the other mode takes the bridge). */
void km_motor_mode_release(km_motor_mode_t *m);

/* The master's frame changed (km_axis.h): the run keeps its start and
 * its direction on the shaft. */
void km_motor_mode_reaxis(km_motor_mode_t *m, const km_axis_t *was, const km_axis_t *now);

/* Stops the motor with `bridge` as the output (stays active). */
void km_motor_mode_stop(km_motor_mode_t *m, km_bridge_mode_t bridge);

/* One tick: the PWM (master's frame) to drive, with *mode PWM; or *mode
 * free/brake once stopped. Needs the measured speed (0.1 deg/s). */
int32_t km_motor_mode_step(km_motor_mode_t *m, const km_control_params_t *p, int32_t position,
                           int32_t speed_ddps, uint32_t dt_us, km_bridge_mode_t *mode);

#endif
