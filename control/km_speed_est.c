/* SPDX-License-Identifier: Apache-2.0 */
/* Speed estimators of the control tick (km_speed_est.h). */
#include "km_speed_est.h"

#include <string.h>

#include "km_axis.h"
#include "km_fixdiv.h"

_Static_assert(100000u % KM_SPEED_WINDOW_US == 0u, "the window's exact fast path");

#define PRV_FAST_SPAN_US ((KM_SPEED_FAST_N - 1u) * 1000u) /* the ring's span at the 1 kHz tick */
_Static_assert(PRV_FAST_SPAN_US == 7000u, "prv_per_fast_span's constants");

static const km_recip_near_t s_span_recip = KM_RECIP_NEAR(PRV_FAST_SPAN_US);
static const km_recip_near_t s_window_recip = KM_RECIP_NEAR(KM_SPEED_WINDOW_US);

/* n / d truncated toward zero, as C's `/`, without a library division
 * (km_udiv_near: a divisor near its nominal value costs a few adds); 0 for d = 0. */
static KM_COMPACT_NOINLINE int32_t prv_sdiv_near(int32_t n, uint32_t d, const km_recip_near_t *c)
{
    const uint32_t q = km_udiv_near(n < 0 ? 0u - (uint32_t)n : (uint32_t)n, d, c);
    return n < 0 ? -(int32_t)q : (int32_t)q;
}

/* d x 1e6 / PRV_FAST_SPAN_US (7,000 us) toward zero for |d| <= 2000:
 * 1e6 / 7000 = 142 + 6/7, and 6|d| / 7 by a 16-bit reciprocal (exact for
 * every such d: tests/unit/control/test_control_fixdiv.c checks each). */
static int32_t prv_per_fast_span(int32_t d)
{
    const uint32_t neg = 0u - ((uint32_t)d >> 31); /* all ones below 0: |d| and the sign back by xor */
    const uint32_t m = ((uint32_t)d ^ neg) - neg;
    const uint32_t q = m * 142u + ((m * 6u * 9363u) >> 16);
    return (int32_t)((q ^ neg) - neg);
}

void km_speed_window_init(km_speed_window_t *w)
{
    memset(w, 0, sizeof *w);
}

int32_t km_speed_window_step(km_speed_window_t *w, int32_t position, uint32_t dt_us)
{
    if (w->have_position) {
        w->acc += km_pos_diff(position, w->last_position);
        w->us += dt_us;
        if (w->us >= KM_SPEED_WINDOW_US) {
            /* 0.1 deg per us -> deg/s; clamped so the product stays in 32 bits */
            const int32_t acc = km_sat(w->acc, 20000);
            w->dps = w->us == KM_SPEED_WINDOW_US ? acc * (100000 / (int32_t)KM_SPEED_WINDOW_US)
                                                 : prv_sdiv_near(acc * 100000, w->us, &s_window_recip);
            w->acc = 0;
            w->us = 0;
        }
    }
    w->last_position = position;
    w->have_position = true;
    return w->dps;
}

void km_speed_fast_init(km_speed_fast_t *f, int32_t position)
{
    memset(f, 0, sizeof *f);
    f->pos[0] = position;
    f->count = 1;
}

KM_COMPACT_NOINLINE int32_t km_speed_fast_step(km_speed_fast_t *f, int32_t position, uint32_t dt_us)
{
    if (dt_us > 100000u) {
        dt_us = 100000u; /* a stalled tick: the estimate stays finite */
    }
    /* span: running sum of the intervals since the oldest sample kept */
    f->head = (uint8_t)((f->head + 1u) % KM_SPEED_FAST_N);
    const uint8_t oldest = (uint8_t)((f->head + 1u) % KM_SPEED_FAST_N);
    f->pos[f->head] = position;
    f->dt[f->head] = dt_us; /* time from the sample before */
    if (f->count < KM_SPEED_FAST_N) {
        if (f->count > 0u) {
            f->span_us += dt_us; /* a ring with no sample yet has no interval */
        }
        f->count++;
    } else {
        f->span_us = f->span_us + dt_us - f->dt[oldest];
    }
    const uint32_t span = f->span_us;
    const uint8_t i = (uint8_t)((f->head + KM_SPEED_FAST_N + 1u - f->count) % KM_SPEED_FAST_N);
    int32_t d = km_pos_diff(position, f->pos[i]);
    d = km_sat(d, 2000); /* keeps d x 1e6 in 32 bits */
#if !KM_CONTROL_COMPACT
    if (d == 0) { /* a shaft holding still (the compact build's prv_per_fast_span gives 0 too) */
        f->ddps = 0;
        return 0;
    }
#endif
    if (span == PRV_FAST_SPAN_US) { /* the steady 1 kHz tick */
        f->ddps = prv_per_fast_span(d);
        return f->ddps;
    }
    f->ddps = prv_sdiv_near(d * 1000000, span, &s_span_recip); /* near 7,000 us: no Newton step */
    return f->ddps;
}

void km_hold_filter_set(km_hold_filter_t *h, bool on, int32_t position)
{
    if (on && !h->on) {
        h->out = position;
        h->frac = 0;
        h->ticks = 0;
    }
    h->on = on;
}

int32_t km_hold_filter_step(km_hold_filter_t *h, int32_t position)
{
    if (!h->on) {
        return position;
    }
    int32_t d = km_pos_diff(position, h->out);
    d = km_sat(d, 100000); /* keeps d x 16 in 32 bits */
    const int32_t e = d * 16 - h->frac;
    if (e > KM_HOLD_FILTER_JUMP * 16 || e < -KM_HOLD_FILTER_JUMP * 16) {
        h->out = position; /* a real push or a new frame (0x16/0x17): taken at once */
        h->frac = 0;
        return position;
    }
    if (h->ticks < KM_HOLD_FILTER_SETTLE) {
        h->ticks++;
        h->frac += e / 8; /* the end of a move: follow it closer */
    } else {
        h->frac += e / 16;
    }
    if (h->frac > 12 || h->frac < -12) { /* 3/4 count: the hysteresis */
        const int32_t n = (h->frac + (h->frac > 0 ? 8 : -8)) / 16;
        h->out = km_pos_add(h->out, n); /* modular: a hold at the wrap */
        h->frac -= n * 16;
    }
    return h->out;
}

void km_speed_obs_reset(km_speed_obs_t *o, int32_t position, int32_t speed_ddps)
{
    o->base = position;
    o->frac = 0;
    /* 0.1 deg/s -> Q16 count per ms: x 65536 / 1000 */
    const int32_t v = km_sat(speed_ddps, 16000);
    o->vel = km_sdiv1000(v * 65536);
}

int32_t km_speed_obs_step(km_speed_obs_t *o, int32_t position, uint32_t dt_us)
{
    const int32_t vmax = 1 << 20; /* 16 counts per ms (1,600 deg/s): keeps vel x dt in 32 bits */
    o->vel = km_sat(o->vel, vmax);
    if (dt_us == 1000u) {
        o->frac += o->vel;
    } else {
        o->frac += km_sdiv1000(o->vel * (int32_t)(dt_us > 2000u ? 2000u : dt_us));
    }
    const int32_t d = km_pos_diff(position, o->base);
    if (d > KM_SPEED_OBS_RESET || d < -KM_SPEED_OBS_RESET) { /* a jump: restart there, at rest */
        o->base = position;
        o->frac = 0;
        o->vel = 0;
        return 0;
    }
    const int32_t r = d * 65536 - o->frac; /* a reading is its angle rounded to a count */
    o->frac += r / (1 << KM_SPEED_OBS_ALPHA_SHIFT);
    o->vel += r / (1 << KM_SPEED_OBS_BETA_SHIFT);
    const int32_t n = (o->frac >= 0 ? o->frac : o->frac - 65535) / 65536; /* floor */
    o->base = km_pos_add(o->base, n);
    o->frac -= n * 65536;
    return (o->vel * 125) / 8192; /* Q16 count per ms -> 0.1 deg/s */
}

int32_t km_speed_obs_frac_u(const km_speed_obs_t *o)
{
    return (o->frac * 125) / 8192;
}
