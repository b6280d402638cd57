/* SPDX-License-Identifier: Apache-2.0 */
/* Host fixture: bench_control's 0x68 stream (docs/protocol.md §5.4; issue
 * 20 criterion 4) sent to a km_plant_rig.h rig: 90 deg/s from -60 to +60
 * deg as one frame every `period` ms, each arriving up to +-5 ms off its
 * time (a reproducible generator whose state the caller keeps), frame k
 * dropped when k mod 17 = 8. The caller steps it one tick at a time and
 * reads, after each tick, the shaft's mean speed over the last 10 ms.
 * Header-only; include after cmocka's headers. */
#ifndef STREAM_RIG_H
#define STREAM_RIG_H

#include <stdbool.h>
#include <stdint.h>

#include "km_plant_rig.h"

typedef struct {
    uint32_t *lcg;      /* the jitter generator's state, the caller's */
    uint32_t period;    /* ms between frames */
    int32_t step;       /* 0.1 deg between frames: 90 deg/s */
    uint32_t n;         /* frames in the stream */
    uint32_t k;         /* the next frame */
    uint32_t arrive;    /* when frame k arrives, ms */
    uint32_t t;         /* ms since sr_start */
    int64_t hist[10];   /* the shaft at the last 10 ticks, udeg */
    uint32_t at_ms;     /* the last tick's time, ms since sr_start */
    bool frames_left;   /* a frame still to come after the last tick */
    int32_t speed_mdps; /* the shaft's mean speed over the 10 ms to the last tick, m deg/s */
} sr_stream_t;

/* Uniform integer in [-5, 5] ms of arrival jitter, from *lcg. */
static inline int32_t sr_jitter(uint32_t *lcg)
{
    *lcg = *lcg * 1103515245u + 12345u;
    return (int32_t)((*lcg >> 16) % 11u) - 5;
}

/* The stream at `period` ms, its first frame's arrival drawn from *lcg. */
static inline void sr_start(sr_stream_t *s, uint32_t period, uint32_t *lcg)
{
    memset(s, 0, sizeof *s);
    s->lcg = lcg;
    s->period = period;
    s->step = (int32_t)(period * 9u / 10u);
    s->n = 1200u / (uint32_t)s->step;
    s->k = 1;
    s->arrive = period + (uint32_t)sr_jitter(lcg);
}

/* One tick: the frames due by now sent, the rig ticked, the speed
 * measured; false (nothing done) once the last frame was sent. */
static inline bool sr_step(sr_stream_t *s, kr_rig_t *r)
{
    if (s->k > s->n) {
        return false;
    }
    while (s->k <= s->n && s->arrive <= s->t) {
        if (s->k % 17u != 8u) {
            assert_true(kr_move(r, KM_MOVE_STREAM, (int16_t)(-600 + (int32_t)s->k * s->step), 0));
        }
        const uint32_t last = s->arrive;
        s->k++;
        const int32_t due = (int32_t)(s->k * s->period) + sr_jitter(s->lcg);
        s->arrive = due < (int32_t)last ? last : (uint32_t)due;
    }
    kr_tick(r);
    const int64_t now = km_plant_shaft_udeg(&r->plant);
    s->at_ms = s->t;
    s->frames_left = s->k <= s->n;
    s->speed_mdps = (int32_t)((now - s->hist[s->t % 10u]) / 10); /* m deg/s over 10 ms */
    s->hist[s->t % 10u] = now;
    s->t++;
    return true;
}

#endif
