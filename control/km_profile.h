/* SPDX-License-Identifier: Apache-2.0 */
/* Trajectory generator: the set-point the position loop follows (moves
 * 0x65..0x67, streams 0x68; docs/protocol.md §5.4). Units: position u =
 * 1e-4 deg, speed u/s, acceleration u/s per ms. Fixed point, no divide
 * instruction on the tick (docs/control-design.md "Trajectory generator"). */
#ifndef KM_PROFILE_H
#define KM_PROFILE_H

#include <stdbool.h>
#include <stdint.h>

#define KM_PROFILE_U_PER_DDEG 1000
#define KM_PROFILE_UPS_PER_DPS 10000
/* u counts from an origin (a multiple of ORIGIN) near the set-point; one
 * move spans at most SPAN, so u and differences of u stay in int32. */
#define KM_PROFILE_ORIGIN_DDEG 65536
#define KM_PROFILE_SPAN_DDEG 900000 /* +-90,000 deg, 250 turns */

typedef struct {
    int32_t origin;   /* 0.1 deg, a multiple of ORIGIN: pos and target are u from it */
    int32_t pos;      /* set-point, u from origin */
    int32_t vel;      /* set-point speed, u/s */
    int32_t target;   /* u from origin */
    int32_t vmax;     /* u/s, > 0 */
    int32_t accel;    /* u/s per ms, > 0 */
    int32_t pos_rem;  /* position remainder, u/1e6 */
    int32_t vel_rem;  /* speed remainder, u/s per 1000 */
    int32_t vel_q_of; /* the vel whose vel / 1000 vel_q holds (the fast build's cache) */
    int32_t vel_q;    /* vel_q_of / 1000 toward zero */
    uint32_t vsq_hi;  /* vmax^2, high and low word, for the braking test */
    uint32_t vsq_lo;
    int32_t s_vel;     /* stream: the targets' speed, u/s */
    int32_t s_vel_q;   /* stream: s_vel / 1000 toward zero, set with it */
    int32_t s_period;  /* stream: the filtered frame period, us (0 = none yet) */
    int32_t s_since;   /* stream: us since the filtered arrival of the newest target */
    int32_t s_lag;     /* stream: how far behind the newest target the set-point runs, us */
    int32_t s_frames;  /* stream: frames fitted into the clock (2..KM_PROFILE_STREAM_FRAMES) */
    int32_t s_step;    /* stream: the targets' step per period, u */
    int32_t s_vr;      /* stream: the speed the set-point heads for, rate-limited, u/s */
    int32_t s_vf;      /* stream: s_vr through the first of two low passes (vel the second), u/s */
    bool stream;       /* following a stream of targets (0x68) */
    bool done;         /* at the target, at rest */
    int32_t s_ahead_q; /* stream: the last ahead (us) / 1000, the next one's first guess */
} km_profile_t;

/* At rest at `pos_ddeg`. */
void km_profile_reset(km_profile_t *p, int32_t pos_ddeg);

/* Move to target at most `vmax_ups` fast, speeding up and braking at `accel`. */
void km_profile_move(km_profile_t *p, int32_t target_ddeg, int32_t vmax_ups, int32_t accel);

/* Move to target in `time_ms` (> 0), no faster than `vlimit_ups`. */
void km_profile_move_time(km_profile_t *p, int32_t target_ddeg, uint32_t time_ms, int32_t vlimit_ups);

/* 0x68 stream constants (docs/control-design.md "Streams"): speed low passes 1/2^SMOOTH_SHIFT a
 * tick, NEAR_U (u) corrected at 1/128 ms, FRAMES fitted arrivals, speed change at accel / ACCEL_DIV. */
#define KM_PROFILE_STREAM_SMOOTH_SHIFT 4
#define KM_PROFILE_STREAM_NEAR_U 5000
#define KM_PROFILE_STREAM_FRAMES 30
#define KM_PROFILE_STREAM_ACCEL_DIV 2
#define KM_PROFILE_STREAM_SLACK_US 12000 /* the reference runs 2 periods + max(period / 2, this) behind */

/* A move in time from the profile's current speed (a retarget or a
 * reversal), at rest on the target after `time_ms` when the limits allow. */
void km_profile_retime(km_profile_t *p, int32_t target_ddeg, uint32_t time_ms, int32_t vlimit_ups,
                       int32_t accel);
/* A stream target, `interval_us` after the previous one. */
void km_profile_stream(km_profile_t *p, int32_t target_ddeg, uint32_t interval_us, int32_t vlimit_ups,
                       int32_t accel);

/* Advance by dt_us. Returns true once at the target and at rest. */
bool km_profile_step(km_profile_t *p, uint32_t dt_us);

/* A target brought within KM_PROFILE_SPAN_DDEG of the set-point, 0.1 deg. */
int32_t km_profile_reach(const km_profile_t *p, int32_t target_ddeg);

/* Set-point in 0.1 deg (rounded, modular) and speed in 0.1 deg/s. */
int32_t km_profile_pos_ddeg(const km_profile_t *p);
int32_t km_profile_vel_ddps(const km_profile_t *p);

#endif
