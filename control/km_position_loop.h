/* SPDX-License-Identifier: Apache-2.0 */
/* Position loop: the PWM that makes the shaft follow the profile's
 * set-point. PWM = feedforward kv x (set-point speed + tau x set-point
 * acceleration), plus friction while the set-point moves; + kp x position
 * error + kd x speed error (set-point speed - measured speed) + ki x
 * integrated error. The integrator runs only while holding (a moving
 * set-point is followed by the feedforward; integrating its lag would wind
 * up into overshoot), stops growing while the output is saturated in the
 * direction it would push, and is bounded by i_max. Output clamped to
 * +-pwm_max. Units: 0.1 deg, 0.1 deg/s, PWM 0..1000, gains km_product.h. */
#ifndef KM_POSITION_LOOP_H
#define KM_POSITION_LOOP_H

#include <stdbool.h>
#include <stdint.h>

#include "km_product.h"

/* Held still, the integrator waits while the shaft returns faster than
 * this toward the target (0.1 deg/s). */
#define KM_HOLD_RETURN_DDPS 20
/* kp_hold and ki_hold apply once the held position (the hold filter's)
 * has not changed for this long (ticks):
 * the end of a move settles on kp and ki, a push on a settled hold is
 * met by the stiffer gains. */
#define KM_HOLD_SETTLED_MS 200
/* ki_hold takes up a push: the shaft more than this away from where the
 * settled hold rested (0.1 deg); a move's residue inside the band is
 * left to ki (a fast integrator there breaks stiction into a jump). */
#define KM_HOLD_PUSH_DDEG 2

typedef struct {
    int32_t i_acc;        /* integrator, PWM x 256000 */
    int32_t last_sp_ddps; /* set-point speed of the last tick, for its acceleration */
    int32_t still_ms;     /* ticks the hold has lasted, up to KM_HOLD_SETTLED_MS */
    int32_t rest_pos;     /* where the shaft rested when the hold settled, 0.1 deg */
} km_position_loop_t;

typedef struct {
    int32_t setpoint_u;    /* profile set-point, 0.001 x 0.1 deg from its origin (km_profile.h) */
    int32_t setpoint_ddps; /* profile speed, 0.1 deg/s */
    int32_t position;      /* measured, 0.1 deg from the same origin */
    int32_t speed_ddps;    /* measured, 0.1 deg/s */
    int32_t pwm_max;       /* output bound, 0..1000 */
    bool integrate;        /* the integrator runs (holding: the set-point is at rest) */
    bool still;            /* the move has ended: the hold band and kp_hold apply */
} km_position_loop_in_t;

void km_position_loop_init(km_position_loop_t *l);

/* Returns the PWM, -pwm_max..pwm_max, in the frame of the set-point. */
int32_t km_position_loop_step(km_position_loop_t *l, const km_control_gains_t *g,
                              const km_position_loop_in_t *in, uint32_t dt_us);

#endif
