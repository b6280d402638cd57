/* SPDX-License-Identifier: Apache-2.0 */
/* Motor mode (docs/protocol.md §5.4 0x6E..0x70): constant PWM, constant
 * speed (a speed loop), and 0x70's runs until a time, an angle or a number
 * of turns, slowing down before a count's end or the travel's edge. The
 * rules and the hand-over with servo mode: docs/control-design.md "Motor
 * mode"; the dispatcher checks the variant and 0x5A preconditions. Speed
 * runs and angle or turn counts are taken on encoder products only (a
 * potentiometer product's dispatcher refuses them, §6): on another
 * variant a speed run is taken as a PWM run and an angle or turn count is
 * not counted, so their paths fold away on a board built as a
 * potentiometer product. */
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

/* The master's frame changed: the run keeps its start and direction. */
void km_motor_mode_reaxis(km_motor_mode_t *m, const km_axis_t *was, const km_axis_t *now);

/* Stops the motor with `bridge` as the output (stays active). */
void km_motor_mode_stop(km_motor_mode_t *m, km_bridge_mode_t bridge);

/* One tick: the PWM (master's frame) with *mode PWM, or *mode free/brake. */
int32_t km_motor_mode_step(km_motor_mode_t *m, const km_control_params_t *p, int32_t position,
                           int32_t speed_ddps, uint32_t dt_us, km_bridge_mode_t *mode);

#endif
