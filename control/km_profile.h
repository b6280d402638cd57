/* SPDX-License-Identifier: Apache-2.0 */
/* Trajectory generator: the set-point the position loop follows.
 *
 * Units: position in u = 0.001 x 0.1 deg (1e-4 deg), speed in u/s
 * (10,000 u/s = 1 deg/s), acceleration in u/s per ms (10 = 1 deg/s^2).
 *
 *  - a move (0x65/0x66/0x67) is time-optimal under a speed and an
 *    acceleration bound: it speeds up at `accel`, cruises at `vmax`, and
 *    brakes on the curve v = sqrt(2 a d) so it stops on the target without
 *    passing it. A new move starts from the current set-point and speed, so
 *    a command during a move blends into it.
 *  - a move in time T from rest: braking and speeding up take T/4 each, the
 *    cruise speed is D / (3T/4); it arrives in T (+ one tick) unless that
 *    speed is above the speed limit, which wins (the move takes longer).
 *  - a stream (0x68): a set-point interpolator. The frame period is a
 *    filtered estimate (the mean of the intervals so far, each taken within
 *    1/4 of the estimate, then 1/64 of each new one; a gap of n periods
 *    counts as n frames: a dropped frame, n from the targets' step when
 *    they move, else from the time), and
 *    each frame's arrival time is the predicted one plus 1/8 of the
 *    difference; the targets' speed is their difference over the
 *    periods between them. The set-point follows a reference that runs at
 *    that speed 2 periods + max(P/2, KM_PROFILE_STREAM_SLACK_US) behind the newest target
 *    (it waits at the target when no newer one comes), at the targets'
 *    speed plus 1/32 ms of the distance to the reference, its speed
 *    changing at most `accel` per ms: arrival jitter and single dropped
 *    frames move neither speed nor acceleration in steps. When the stream
 *    stops (no target for the lag), the set-point brakes on the last
 *    target as a move, at 8 x `accel`. Speed bounded
 *    by `vmax`.
 * step(state, dt) advances it, in pieces of at most 2 ms; speeds are cut
 * to 2^30 u/s (107,374 deg/s, past any 0x5D) so a piece stays in 32 bits.
 * No float, no divide instruction (the M0 has none) in a 1 ms tick: the
 * quotients by 1000 are reciprocal multiplies (km_fixdiv.h), the braking
 * square root is 32-bit (2 bits a step) and taken only while braking. */
#ifndef KM_PROFILE_H
#define KM_PROFILE_H

#include <stdbool.h>
#include <stdint.h>

#define KM_PROFILE_U_PER_DDEG 1000
#define KM_PROFILE_UPS_PER_DPS 10000
/* Positions are modular int32 0.1 deg (km_axis.h); the profile keeps u
 * from an origin, a multiple of KM_PROFILE_ORIGIN_DDEG, moved at a command
 * to the one nearest the set-point when the set-point is more than half an
 * origin from it (0 for every set-point within +-3,276.8 deg). One move
 * spans at most KM_PROFILE_SPAN_DDEG: a target
 * farther from the set-point is brought to that distance (the short way
 * round). So u from the origin stays within +-(span + origin/2) =
 * +-93,277 deg (the position loop takes +-100,000 deg) and differences
 * of two u values within int32 (docs/protocol-decisions.md "Multi-turn
 * position and its wrap"). */
#define KM_PROFILE_ORIGIN_DDEG 65536
#define KM_PROFILE_SPAN_DDEG 900000 /* +-90,000 deg, 250 turns */

typedef struct {
    int32_t
        origin;  /* 0.1 deg (modular, a multiple of KM_PROFILE_ORIGIN_DDEG): pos and target are u from it */
    int32_t pos; /* set-point, u from origin */
    int32_t vel; /* set-point speed, u/s */
    int32_t target;   /* u from origin */
    int32_t vmax;     /* u/s, > 0 */
    int32_t accel;    /* u/s per ms, > 0 */
    int32_t pos_rem;  /* position remainder, u/1e6 */
    int32_t vel_rem;  /* speed remainder, u/s per 1000 */
    uint32_t vsq_hi;  /* vmax^2 (high, low word), set with vmax by a move: */
    uint32_t vsq_lo;  /* the braking test of every tick compares with it */
    int32_t s_vel;    /* stream: the targets' speed, u/s */
    int32_t s_period; /* stream: the filtered frame period, us (0 = none yet) */
    int32_t s_since;  /* stream: us since the filtered arrival of the newest target */
    int32_t s_lag;    /* stream: how far behind the newest target the set-point runs, us */
    int32_t s_frames; /* stream: intervals averaged into s_period (at most 62) */
    int32_t s_step;   /* stream: the targets' step per period, u */
    bool stream;      /* following a stream of targets (0x68) */
    bool done;        /* at the target, at rest */
} km_profile_t;

/* At rest at `pos_ddeg`. */
void km_profile_reset(km_profile_t *p, int32_t pos_ddeg);

/* Move to target at most `vmax_ups` fast, speeding up and braking at `accel`. */
void km_profile_move(km_profile_t *p, int32_t target_ddeg, int32_t vmax_ups, int32_t accel);

/* Move to target in `time_ms` (> 0), no faster than `vlimit_ups`. */
void km_profile_move_time(km_profile_t *p, int32_t target_ddeg, uint32_t time_ms, int32_t vlimit_ups);

#define KM_PROFILE_STREAM_SLACK_US 8000 /* the reference runs 2 periods + max(period / 2, this) behind */

/* A move in time that may start while the profile moves (a retarget or a
 * reversal): from the profile's speed, changing speed at `accel` (u/s per
 * ms) both ways, arriving at rest on the target after `time_ms` when the
 * speed limit and `accel` allow (braking harder when even stopping on the
 * target needs more); from rest it is km_profile_move_time. */
void km_profile_retime(km_profile_t *p, int32_t target_ddeg, uint32_t time_ms, int32_t vlimit_ups,
                       int32_t accel);
/* A stream target, `interval_us` after the previous one; `accel` bounds
 * the set-point's speed change (u/s per ms), `vlimit_ups` its speed. */
void km_profile_stream(km_profile_t *p, int32_t target_ddeg, uint32_t interval_us, int32_t vlimit_ups,
                       int32_t accel);

/* Advance by dt_us. Returns true once at the target and at rest. */
bool km_profile_step(km_profile_t *p, uint32_t dt_us);

/* A target as a move takes it: within KM_PROFILE_SPAN_DDEG of the
 * set-point (modular), 0.1 deg. */
int32_t km_profile_reach(const km_profile_t *p, int32_t target_ddeg);

/* Set-point in 0.1 deg (rounded, modular) and speed in 0.1 deg/s. */
int32_t km_profile_pos_ddeg(const km_profile_t *p);
int32_t km_profile_vel_ddps(const km_profile_t *p);

#endif
