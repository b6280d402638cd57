/* SPDX-License-Identifier: Apache-2.0 */
/* Trajectory generator (km_profile.h; docs/control-design.md). */
#include "km_profile.h"

#include <string.h>

#include "km_axis.h"
#include "km_fixdiv.h"

/* Bounds that keep a piece's products in 32 bits. */
#define STEP_MAX_US 2000u /* a late 1 ms tick stays one piece */
#define ACCEL_MAX 1000000 /* u/s per ms */
#define VMAX_MAX 0x3FFFFFFF
_Static_assert(ACCEL_MAX % KM_PROFILE_STREAM_ACCEL_DIV == 0, "prv_stream_end's bound: a whole multiple");

static int32_t prv_abs(int32_t v)
{
    return v < 0 ? -v : v;
}

/* The origin for a set-point at `ddeg`: the nearest multiple, modular. */
static int32_t prv_origin_for(int32_t ddeg)
{
    const uint32_t q = (uint32_t)KM_PROFILE_ORIGIN_DDEG;
    return km_s32(((uint32_t)ddeg + q / 2u) & ~(q - 1u));
}

/* |pos| below this (u): the set-point is within half an origin of it. */
#define PRV_NEAR_U (KM_PROFILE_ORIGIN_DDEG / 2 * KM_PROFILE_U_PER_DDEG)

/* Moves the origin to the one nearest the set-point (pos and target by
 * whole origins); no work when it is already near. */
static void prv_rebase(km_profile_t *p)
{
    if (p->pos < PRV_NEAR_U && p->pos >= -PRV_NEAR_U) {
        return;
    }
    const int32_t now = prv_origin_for(km_profile_pos_ddeg(p));
    const int32_t shift = km_pos_diff(p->origin, now);
    if (shift != 0) {
        const uint32_t shift_u = (uint32_t)shift * (uint32_t)KM_PROFILE_U_PER_DDEG;
        p->origin = now;
        p->pos = km_s32((uint32_t)p->pos + shift_u);
        p->target = km_s32((uint32_t)p->target + shift_u);
    }
}

/* A target (0.1 deg) as u from the origin, after prv_rebase. */
static int32_t prv_target_u(const km_profile_t *p, int32_t ddeg)
{
    return km_pos_diff(km_profile_reach(p, ddeg), p->origin) * KM_PROFILE_U_PER_DDEG;
}

int32_t km_profile_reach(const km_profile_t *p, int32_t target_ddeg)
{
#if !KM_CONTROL_COMPACT
    /* near the origin: within the span without a divide (the compact
     * build divides: the general case below gives the same target) */
    const int32_t rel = km_pos_diff(target_ddeg, p->origin);
    const int32_t easy = KM_PROFILE_SPAN_DDEG - KM_PROFILE_ORIGIN_DDEG;
    if (p->pos < PRV_NEAR_U && p->pos >= -PRV_NEAR_U && rel <= easy && rel >= -easy) {
        return target_ddeg;
    }
#endif
    const int32_t at = km_profile_pos_ddeg(p);
    const int32_t d = km_pos_diff(target_ddeg, at);
    if (d > KM_PROFILE_SPAN_DDEG) {
        return km_pos_add(at, KM_PROFILE_SPAN_DDEG);
    }
    if (d < -KM_PROFILE_SPAN_DDEG) {
        return km_pos_add(at, -KM_PROFILE_SPAN_DDEG);
    }
    return target_ddeg;
}

/* m (u, >= 0) over t (>= 1) periods of 1/scale s as u/s, at most `vmax`
 * (no 32-bit overflow for any m). */
static KM_COMPACT_NOINLINE int32_t prv_rate(int32_t m, int32_t t, int32_t scale, int32_t vmax)
{
    const int32_t q = m / t;
    if (q >= vmax / scale + 1) {
        return vmax;
    }
    const int32_t v = q * scale + ((m % t) * scale) / t;
    return v < vmax ? v : vmax;
}

void km_profile_reset(km_profile_t *p, int32_t pos_ddeg)
{
    memset(p, 0, sizeof *p);
    p->origin = prv_origin_for(pos_ddeg);
    p->pos = km_pos_diff(pos_ddeg, p->origin) * KM_PROFILE_U_PER_DDEG;
    p->target = p->pos;
    p->vmax = 1;
    p->vsq_lo = 1u;
    p->accel = 1;
    p->done = true;
}

/* A command's target (0.1 deg) as u from the rebased origin. */
static int32_t prv_begin(km_profile_t *p, int32_t target_ddeg)
{
    prv_rebase(p);
    return prv_target_u(p, target_ddeg);
}

/* km_profile_move to `tgt` (u from the origin, prv_begin's). */
static void prv_move_u(km_profile_t *p, int32_t tgt, int32_t vmax_ups, int32_t accel)
{
    p->target = tgt;
    p->vmax = km_clamp(vmax_ups, 1, VMAX_MAX);
    p->vsq_hi = km_umulhi((uint32_t)p->vmax, (uint32_t)p->vmax);
    p->vsq_lo = (uint32_t)p->vmax * (uint32_t)p->vmax;
    p->accel = km_clamp(accel, 1, ACCEL_MAX);
    p->stream = false;
    p->s_period = 0; /* a stream that follows starts afresh */
    p->done = false;
}

void km_profile_move(km_profile_t *p, int32_t target_ddeg, int32_t vmax_ups, int32_t accel)
{
    prv_move_u(p, prv_begin(p, target_ddeg), vmax_ups, accel);
}

/* km_profile_move_time to `tgt` (u from the origin, prv_begin's). */
static void prv_move_time_u(km_profile_t *p, int32_t tgt, uint32_t time_ms, int32_t vlimit_ups)
{
    const int32_t d = prv_abs(tgt - p->pos);
    if (time_ms > 65535u) {
        time_ms = 65535u;
    }
    const int32_t ta = time_ms >= 4u ? (int32_t)(time_ms / 4u) : 1;
    const int32_t tc = (int32_t)time_ms - ta > 0 ? (int32_t)time_ms - ta : 1;
    /* cruise D / (3T/4); the speed limit wins */
    int32_t v = prv_rate(d, tc, 1000, vlimit_ups); /* ms */
    if (v < 1) {
        v = 1;
    }
    const int32_t a = v / ta > 0 ? v / ta : 1;
    prv_move_u(p, tgt, v, a);
}

void km_profile_move_time(km_profile_t *p, int32_t target_ddeg, uint32_t time_ms, int32_t vlimit_ups)
{
    prv_move_time_u(p, prv_begin(p, target_ddeg), time_ms, vlimit_ups);
}

/* The cruise speed (0.1 deg/s) of a retimed move of `dm` u in `t` ms from
 * `v0` (+ toward the target) at `a` (docs/tuning.md "Moves"). */
static int32_t prv_retime_cruise(int32_t v0, int32_t dm, int32_t t, int32_t a)
{
    if (v0 > 0) {
        const int32_t s0 = (int32_t)(((uint32_t)v0 * (uint32_t)v0) / (2u * (uint32_t)a));
        const int32_t tl = t - v0 / a;
        if (tl > 0 && dm > s0) {
            const int32_t vc = (dm - s0) / tl;
            if (vc <= v0) {
                return vc;
            }
        }
    }
    /* b = v0 + a t < 2^27, c = a dm + v0^2 / 2 < 2^41 (two words), disc = b^2 - 4c */
    const int32_t b = v0 + a * t;
    const uint32_t v = v0 < 0 ? 0u - (uint32_t)v0 : (uint32_t)v0, adm = (uint32_t)(a * dm);
    const uint32_t v_hi = km_umulhi(v, v), v_lo = v * v;
    uint32_t c_hi = v_hi >> 1, c_lo = (v_lo >> 1) | (v_hi << 31);
    c_lo += adm;
    c_hi += c_lo < adm ? 1u : 0u;
    const uint32_t ub = (uint32_t)b, b_hi = km_umulhi(ub, ub), b_lo = ub * ub;
    const uint32_t f_hi = (c_hi << 2) | (c_lo >> 30), f_lo = c_lo << 2;
    if (b <= 0 || b_hi < f_hi || (b_hi == f_hi && b_lo < f_lo)) {
        return (int32_t)km_isqrt(c_hi, c_lo); /* the triangle: as fast as a allows */
    }
    const uint32_t d_hi = b_hi - f_hi - (b_lo < f_lo ? 1u : 0u);
    return (int32_t)((ub - km_isqrt(d_hi, b_lo - f_lo)) >> 1);
}

/* `acc`, or the harder braking `v0` needs to stop within `dabs` u. */
static int32_t prv_brake_accel(int32_t v0, int32_t dabs, int32_t acc)
{
    if (v0 <= 0) {
        return acc;
    }
    const uint32_t need = ((uint32_t)v0 * (uint32_t)v0) / (2u * (uint32_t)(dabs > 0 ? dabs : 1)) + 1u;
    if (need * 1000u <= (uint32_t)acc) {
        return acc;
    }
    return need > (uint32_t)(ACCEL_MAX / 1000) ? ACCEL_MAX : (int32_t)need * 1000;
}

void km_profile_retime(km_profile_t *p, int32_t target_ddeg, uint32_t time_ms, int32_t vlimit_ups,
                       int32_t accel)
{
    const int32_t tgt = prv_begin(p, target_ddeg);
    const int32_t d = tgt - p->pos;
    const int32_t dabs = prv_abs(d);
    const int32_t a = km_sdiv1000(km_clamp(accel, 1, ACCEL_MAX));
    if (p->done || p->stream || p->vel == 0 || dabs > 1000000 || time_ms == 0u || a < 1) {
        prv_move_time_u(p, tgt, time_ms, vlimit_ups);
        return;
    }
    const int32_t v0 = km_sdiv1000(d >= 0 ? p->vel : -p->vel); /* 0.1 deg/s toward the target */
    const int32_t t = time_ms > 65535u ? 65535 : (int32_t)time_ms;
    int32_t vc = prv_retime_cruise(v0, dabs, t, a);
    const int32_t vlim = km_sdiv1000(vlimit_ups);
    vc = km_clamp(vc, 1, vlim);
    prv_move_u(p, tgt, vc * 1000, prv_brake_accel(v0, dabs, a * 1000));
}

/* d (u) over `us` (>= 100) as u/s, at most `vmax` in size; 32-bit. */
static int32_t prv_speed_us(int32_t d, int32_t us, int32_t vmax)
{
    const int32_t t = us / 100 > 0 ? us / 100 : 1; /* 0.1 ms */
    const int32_t v = prv_rate(prv_abs(d), t, 10000, vmax);
    return d < 0 ? -v : v;
}

/* The periods since the previous target (1 + frames lost), 1..8: from the
 * step `d` when the stream moves, else from the time. */
static int32_t prv_stream_periods(const km_profile_t *p, int32_t d)
{
    int32_t n = (p->s_since + p->s_period / 2) / p->s_period;
    const uint32_t a = (uint32_t)prv_abs(d), b = (uint32_t)prv_abs(p->s_step);
    if (b != 0u && a / b <= 8u && (d >= 0) == (p->s_step >= 0)) {
        n = (int32_t)((a + b / 2u) / b);
    }
    return km_clamp(n, 1, 8);
}

/* The stream's clock (phase and period) on a target `n` periods after the
 * previous one: a least-squares line through the arrivals
 * (docs/control-design.md "Streams"). */
static void prv_stream_clock(km_profile_t *p, int32_t n)
{
    const int32_t late = p->s_since - n * p->s_period;
    const int32_t k = p->s_frames, kk = (k + 1) * (k + 2);
    const int32_t q = k < KM_PROFILE_STREAM_FRAMES ? 1000000 : p->s_period / 4;
    const int32_t lp = km_sat(late, q);
    p->s_since = late - late * (2 * (2 * k + 1)) / kk; /* alpha = 2(2k+1)/((k+1)(k+2)) */
    p->s_period += lp * 6 / (kk * n);                  /* beta = 6/((k+1)(k+2)) */
    p->s_period = p->s_period < 1000 ? 1000 : p->s_period;
    p->s_frames = k < KM_PROFILE_STREAM_FRAMES ? k + 1 : k;
}

void km_profile_stream(km_profile_t *p, int32_t target_ddeg, uint32_t interval_us, int32_t vlimit_ups,
                       int32_t accel)
{
    const int32_t tgt = prv_begin(p, target_ddeg);
    const int32_t iv = interval_us > 1000000u ? 1000000 : (interval_us < 1000u ? 1000 : (int32_t)interval_us);
    int32_t n = 1;
    if (p->s_period <= 0) {
        p->s_period = iv;
        p->s_since = 0;
        p->s_frames = 2; /* two arrivals fitted: this one and the move's */
        p->s_step = 0;
    } else {
        n = prv_stream_periods(p, tgt - p->target);
        prv_stream_clock(p, n);
    }
    p->vmax = km_clamp(vlimit_ups, 1, VMAX_MAX);
    p->accel = km_clamp(accel, 1, ACCEL_MAX);
    p->s_vel = prv_speed_us(tgt - p->target, n * p->s_period, p->vmax);
    p->s_vel_q = km_sdiv1000(p->s_vel);
    p->s_step = (tgt - p->target) / n;
    p->s_lag = 2 * p->s_period +
               (p->s_period / 2 > KM_PROFILE_STREAM_SLACK_US ? p->s_period / 2 : KM_PROFILE_STREAM_SLACK_US);
    p->target = tgt;
    if (!p->stream) {
        p->s_vr = p->vel;
        p->s_vf = p->vel;
    }
    p->stream = true;
    p->done = false;
}

/* vel / 1000 toward zero, divided only when vel changed since the last. */
static int32_t prv_vel_q(km_profile_t *p)
{
    if (p->vel != p->vel_q_of) {
        p->vel_q_of = p->vel;
        p->vel_q = km_sdiv1000(p->vel);
    }
    return p->vel_q;
}

/* pos += vel * dt / 1e6 exactly, remainder carried (dt <= 2000; |pos_rem|
 * < 4e6 before normalising). Returns vel / 1000. */
static int32_t prv_advance(km_profile_t *p, uint32_t dt_us)
{
    const int32_t q = prv_vel_q(p), r = p->vel - q * 1000;
    if (dt_us == 1000u) {
        p->pos += q;
        p->pos_rem += r * 1000;
    } else {
        const int32_t qd = q * (int32_t)dt_us; /* |q| < 2^20 */
        const int32_t qq = km_sdiv1000(qd);
        p->pos += qq;
        p->pos_rem += (qd - qq * 1000) * 1000 + r * (int32_t)dt_us;
    }
    while (p->pos_rem >= 1000000) {
        p->pos++;
        p->pos_rem -= 1000000;
    }
    while (p->pos_rem <= -1000000) {
        p->pos--;
        p->pos_rem += 1000000;
    }
    return q;
}

/* The braking-curve speed min(floor(sqrt(k x d)), vmax); no root above vmax^2. */
static int32_t prv_brake_speed(const km_profile_t *p, uint32_t k, uint32_t d)
{
    const uint32_t hi = km_umulhi(k, d), lo = k * d;
    if (hi > p->vsq_hi || (hi == p->vsq_hi && lo >= p->vsq_lo)) {
        return p->vmax;
    }
#if !KM_CONTROL_COMPACT
    if ((uint32_t)p->vmax < (1u << 28)) {
        return (int32_t)km_isqrt56_fast(hi, lo);
    }
#endif
    return (int32_t)km_isqrt(hi, lo);
}

/* The speed change a piece allows, remainder carried (0 <= vel_rem < 1000). */
static int32_t prv_dv(km_profile_t *p, uint32_t dt_us)
{
    if (dt_us == 1000u && p->vel_rem >= 0) {
        return p->accel; /* 0 <= rem < 1000: rem stays */
    }
    const int32_t dv = p->accel * (int32_t)dt_us + p->vel_rem;
    const int32_t dvq = km_sdiv1000(dv);
    p->vel_rem = dv - dvq * 1000;
    return dvq;
}

/* `v` moved toward `want` by at most `dv` (>= 0): a speed's rate limit. */
static int32_t prv_toward(int32_t v, int32_t want, int32_t dv)
{
    return km_clamp(want, v - dv, v + dv);
}

/* One step of a stream speed's low pass from `v` toward `to` (exactly there once within a step). */
static KM_COMPACT_NOINLINE int32_t prv_smooth(int32_t v, int32_t to)
{
    const int32_t d = to - v, n = 1 << KM_PROFILE_STREAM_SMOOTH_SHIFT;
    return v + (d >= n || d <= -n ? d / n : d);
}

/* At rest on the target: the move or stream is over. */
static void prv_arrive(km_profile_t *p)
{
    p->pos = p->target;
    p->pos_rem = 0;
    p->vel = 0;
    p->vel_q_of = 0; /* 0 / 1000: the reported speed needs no divide */
    p->vel_q = 0;
    p->vel_rem = 0;
    p->done = true;
}

/* The stream is over (no newer target within the lag): a set-point there
 * or past it stops on the target, else it brakes onto it as a move. */
static void prv_stream_end(km_profile_t *p)
{
    const int32_t left = p->target - p->pos;
    if (left == 0 || (left > 0) != (p->vel > 0)) {
        prv_arrive(p);
        return;
    }
    p->stream = false;
    p->accel = km_clamp(p->accel * KM_PROFILE_STREAM_ACCEL_DIV, 1, ACCEL_MAX);
    p->vsq_hi = km_umulhi((uint32_t)p->vmax, (uint32_t)p->vmax);
    p->vsq_lo = (uint32_t)p->vmax * (uint32_t)p->vmax;
}

/* ahead / 1000 for ahead > 0: the last quotient, or one less, while the
 * reference moves on by up to 1 ms a tick; a divide only after a jump (a
 * set-point). */
static int32_t prv_ahead_ms(km_profile_t *p, int32_t ahead)
{
    int32_t q = p->s_ahead_q;
    const int32_t r = ahead - q * 1000;
    if (r < 0 && r >= -1000) {
        q--;
    } else if (r < 0 || r >= 1000) {
        q = km_sdiv1000(ahead);
    }
    p->s_ahead_q = q;
    return q;
}

/* The speed a stream heads for: the targets' speed plus 1/128 ms of the
 * distance to the reference within KM_PROFILE_STREAM_NEAR_U, 1/64 ms
 * beyond; at most vmax. */
static int32_t prv_stream_want(km_profile_t *p, int32_t ahead)
{
    const int32_t vff = p->s_vel;
    const int32_t ref = p->target - p->s_vel_q * prv_ahead_ms(p, ahead);
    int32_t err = ref - p->pos;
    const int32_t emax = p->vmax / 32 + 1, near = KM_PROFILE_STREAM_NEAR_U;
    err = km_sat(err, emax);
    const int32_t corr = err * 8 + (err - km_sat(err, near)) * 8; /* x 16 beyond near */
    const int32_t want = vff + corr;
    return km_sat(want, p->vmax);
}

/* A stream piece: follow the reference s_lag behind the newest target, or
 * brake onto it once no newer target came. */
static void prv_step_stream(km_profile_t *p, uint32_t dt_us)
{
    const int32_t ahead = p->s_lag - p->s_since; /* us the reference is behind the target */
    if (ahead <= 0) {
        prv_stream_end(p);
        return;
    }
    const int32_t want = prv_stream_want(p, ahead);
    const int32_t dv = prv_dv(p, dt_us);
    p->s_vr = prv_toward(p->s_vr, want, dv);
    p->s_vf = prv_smooth(p->s_vf, p->s_vr);
    p->vel = prv_smooth(p->vel, p->s_vf);
    (void)prv_advance(p, dt_us);
    if (p->target == p->pos && p->vel == 0) {
        prv_arrive(p);
    }
}

/* One piece of at most STEP_MAX_US. */
static void prv_step(km_profile_t *p, uint32_t dt_us)
{
    const int32_t e = p->target - p->pos;
    if (p->stream) {
        prv_step_stream(p, dt_us);
        return;
    }
    const int32_t dv = prv_dv(p, dt_us);
    /* the braking speed from where this piece ends */
    const int32_t vq = prv_abs(prv_vel_q(p));
    int32_t d = prv_abs(e) - (dt_us == 1000u ? vq : km_sdiv1000(vq * (int32_t)dt_us));
    if (d < 0) {
        d = 0;
    }
    const int32_t vb = prv_brake_speed(p, 2000u * (uint32_t)p->accel, (uint32_t)d);
    const int32_t want = e >= 0 ? vb : -vb;
    p->vel = prv_toward(p->vel, want, dv);
    const int32_t q = prv_abs(prv_advance(p, dt_us));
    const int32_t left = p->target - p->pos;
    /* arrived or crossed: stop on the target */
    if (left == 0 || ((left > 0) != (e > 0) && e != 0) || (prv_abs(left) <= q + 1 && prv_abs(p->vel) <= dv)) {
        prv_arrive(p);
    }
}

bool km_profile_step(km_profile_t *p, uint32_t dt_us)
{
    while (!p->done && dt_us > 0u) {
        const uint32_t piece = dt_us > STEP_MAX_US ? STEP_MAX_US : dt_us;
        if (p->s_period > 0 && p->s_since < 4000000) { /* a stream's clock */
            p->s_since += (int32_t)piece;
        }
        prv_step(p, piece);
        dt_us -= piece;
    }
    return p->done;
}

int32_t km_profile_pos_ddeg(const km_profile_t *p)
{
    const int32_t h = KM_PROFILE_U_PER_DDEG / 2;
    const int32_t from = km_sdiv1000(p->pos >= 0 ? p->pos + h : p->pos - h); /* rounded half away from 0 */
    return km_pos_add(p->origin, from);
}

int32_t km_profile_vel_ddps(const km_profile_t *p)
{
    return p->vel == p->vel_q_of ? p->vel_q : km_sdiv1000(p->vel);
}
