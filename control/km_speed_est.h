/* SPDX-License-Identifier: Apache-2.0 */
/* Speed estimation from the tick's positions: 0x47 over a 20 ms window,
 * the loops' damping speed over KM_SPEED_FAST_N samples, the hold
 * filter for the position a still hold works on and reports (0x46), and
 * the observer of position and speed between counts a 0x68 stream runs on.
 * docs/control-design.md "Speed estimates", docs/tuning.md. */
#ifndef KM_SPEED_EST_H
#define KM_SPEED_EST_H

#include <stdbool.h>
#include <stdint.h>

#define KM_SPEED_WINDOW_US 20000u
#define KM_SPEED_FAST_N 8u

typedef struct {
    int32_t last_position; /* 0.1 deg */
    int32_t acc;           /* 0.1 deg moved since the last update */
    uint32_t us;           /* time accumulated for the estimate */
    int32_t dps;           /* the estimate, deg/s */
    bool have_position;
} km_speed_window_t;

typedef struct {
    int32_t pos[KM_SPEED_FAST_N]; /* 0.1 deg, ring */
    uint32_t dt[KM_SPEED_FAST_N]; /* us each sample closed */
    uint32_t span_us;             /* sum of dt over the ring */
    uint8_t head, count;
    int32_t ddps; /* the estimate, 0.1 deg/s */
} km_speed_fast_t;

#define KM_HOLD_FILTER_SETTLE 200 /* ticks at 1/8 before 1/16 (the end of a move settles) */
#define KM_HOLD_FILTER_JUMP 8     /* counts: a real push, taken at once */

typedef struct {
    int32_t out;   /* the position given out, 0.1 deg */
    int32_t frac;  /* filtered position - out, 1/16 x 0.1 deg */
    int32_t ticks; /* since it started, up to KM_HOLD_FILTER_SETTLE */
    bool on;
} km_hold_filter_t;

/* The observer: an alpha-beta filter, estimate base + frac. */
#define KM_SPEED_OBS_ALPHA_SHIFT 3 /* alpha = 1/8 a tick */
#define KM_SPEED_OBS_BETA_SHIFT 8  /* beta = 1/256 a tick */
#define KM_SPEED_OBS_RESET 100     /* counts: a reading this far off restarts it */

typedef struct {
    int32_t base; /* 0.1 deg (modular) */
    int32_t frac; /* Q16 count above base, 0..65535 */
    int32_t vel;  /* Q16 count per ms */
} km_speed_obs_t;

/* Restarts the observer at `position` (0.1 deg), moving at `speed_ddps`. */
void km_speed_obs_reset(km_speed_obs_t *o, int32_t position, int32_t speed_ddps);
/* Takes this tick's reading; returns the speed estimate, 0.1 deg/s. */
int32_t km_speed_obs_step(km_speed_obs_t *o, int32_t position, uint32_t dt_us);
/* The estimate's part above base in 0.001 x 0.1 deg (0..999). */
int32_t km_speed_obs_frac_u(const km_speed_obs_t *o);

void km_speed_window_init(km_speed_window_t *w);
/* Returns the current estimate, deg/s (held until a window completes). */
int32_t km_speed_window_step(km_speed_window_t *w, int32_t position, uint32_t dt_us);

void km_speed_fast_init(km_speed_fast_t *f, int32_t position);
/* Returns the current estimate, 0.1 deg/s. */
int32_t km_speed_fast_step(km_speed_fast_t *f, int32_t position, uint32_t dt_us);

/* Starts (on) or stops (off) filtering; starting takes `position` as is. */
void km_hold_filter_set(km_hold_filter_t *h, bool on, int32_t position);
/* Returns the position to use this tick: filtered when on, else `position`. */
int32_t km_hold_filter_step(km_hold_filter_t *h, int32_t position);

#endif
