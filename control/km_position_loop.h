/* SPDX-License-Identifier: Apache-2.0 */
/* Position loop: the PWM that makes the shaft follow the profile's
 * set-point (feedforward, PD, an integrator only while holding). Units
 * 0.1 deg, 0.1 deg/s, PWM 0..1000, gains km_product.h; docs/tuning.md. */
#ifndef KM_POSITION_LOOP_H
#define KM_POSITION_LOOP_H

#include <stdbool.h>
#include <stdint.h>

#include "km_product.h"

/* The hold's gain switches (docs/tuning.md "Three phases of one move"). */
#define KM_HOLD_RETURN_DDPS 20    /* integrator waits while the shaft returns faster */
#define KM_HOLD_SETTLED_MS 200    /* held position unchanged this long: kp_hold */
#define KM_HOLD_PUSH_DDEG 2       /* pushed this far from rest: ki_hold */
#define KM_HOLD_KI_GROW_Q6 5      /* ki_hold grows by 5/64 of itself per 0.1 deg of error */
#define KM_HOLD_BLEED_DDEG 4      /* a push returning this close: its integrator bleeds */
#define KM_HOLD_RETURN_BLEED_Q9 5 /* ... by 5/512 a tick */
#define KM_HOLD_PAST_DDEG 2       /* the shaft this far past the target the way the integrator pushes: */
#define KM_HOLD_PAST_BLEED 8      /* ... it bleeds 1/8 a tick instead of integrating */

/* kp and kd shifted down while a 0x68 stream runs (docs/tuning.md "0x68 streams"). */
/* A pushed hold's integrator refinements (1, the default): ki_hold growing
 * with the error, the bleed while the shaft returns and inside the band
 * (prv_hold_ki, docs/tuning.md); 0: a still hold integrates at ki as a
 * moving one (the 32 KiB STM32G031F6 build, docs/footprint.md "What gives
 * way"). */
#ifndef KM_FEATURE_HOLD_KI
#define KM_FEATURE_HOLD_KI 1
#endif
#define KM_STREAM_KP_SHIFT 1
#define KM_STREAM_KD_SHIFT 3

typedef struct {
    int32_t i_acc;        /* integrator, PWM x 256000 */
    int32_t i_pwm_of;     /* the i_acc whose / 256000 i_pwm holds (the fast build's cache) */
    int32_t i_pwm;        /* i_pwm_of / 256000 toward zero */
    int32_t last_sp_ddps; /* set-point speed of the last tick, for its acceleration */
    int32_t last_sp_sub;  /* and its part below 0.1 deg/s (a stream's), 0.001 x 0.1 deg/s */
    int32_t still_ms;     /* ticks the hold has lasted, up to KM_HOLD_SETTLED_MS */
    int32_t rest_pos;     /* where the shaft rested when the hold settled, 0.1 deg */
} km_position_loop_t;

typedef struct {
    int32_t setpoint_u;    /* profile set-point, 0.001 x 0.1 deg from its origin (km_profile.h) */
    int32_t setpoint_ddps; /* profile speed, 0.1 deg/s */
    int32_t setpoint_sub;  /* and its part below 0.1 deg/s, 0.001 x 0.1 deg/s (-999..999) */
    int32_t position;      /* measured, 0.1 deg from the same origin */
    int32_t speed_ddps;    /* measured, 0.1 deg/s */
    int32_t pwm_max;       /* output bound, 0..1000 */
    bool integrate;        /* the integrator runs (holding: the set-point is at rest) */
    bool unwind;           /* it may shrink (holding, also under a protection's hold) */
    bool still;            /* the move has ended: the hold band and kp_hold apply */
    bool stream;           /* a 0x68 stream runs: kp and kd lowered (KM_STREAM_KP_SHIFT, _KD_) */
} km_position_loop_in_t;

void km_position_loop_init(km_position_loop_t *l);

/* Returns the PWM, -pwm_max..pwm_max, in the frame of the set-point. */
int32_t km_position_loop_step(km_position_loop_t *l, const km_control_gains_t *g,
                              const km_position_loop_in_t *in, uint32_t dt_us);

#endif
