/* SPDX-License-Identifier: Apache-2.0 */
/* Speed estimation from the position samples of the control tick.
 *  - km_speed_window_t: the reported speed (0x47, deg/s): position change
 *    over a 20 ms window. At 0.1 deg resolution a 1 ms difference would
 *    quantise speed to 100 deg/s steps.
 *  - km_speed_fast_t: the position loop's damping input (0.1 deg/s):
 *    position change over the last KM_SPEED_FAST_N ticks (8 ms at 1 kHz,
 *    12.5 deg/s resolution, 4 ms of lag against the plant's ~28 ms).
 *  - km_hold_filter_t: the position a hold works on and reports (0x46)
 *    while servo mode holds still: a first-order low pass (1/8 per tick
 *    for KM_HOLD_FILTER_SETTLE ticks, then 1/16;
 *    a reading more than KM_HOLD_FILTER_JUMP away is taken as is) whose output moves
 *    only when the filtered value is more than 3/4 count away from it
 *    (hysteresis), so sensor noise of about a count neither reaches the
 *    bridge nor 0x46 (docs/tuning.md). Off, it passes the reading through. */
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
