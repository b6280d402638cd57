/* SPDX-License-Identifier: Apache-2.0 */
/* The control tick's divide-free arithmetic (issue 8: the Cortex-M0 has no
 * divide instruction) against C's own: control/km_fixdiv.h's reciprocal
 * quotients, and the profile and speed estimator rewritten with them, step
 * for step against the division-based code they replaced (kept here as the
 * reference). Equal results, not bounded errors: every case must match
 * exactly. The motion they produce is docs/protocol.md §5.4's (0x65..0x68). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_fixdiv.h"
#include "km_profile.h"
#include "km_speed_est.h"

static uint32_t s_rng = 0x2545F491u;

static uint32_t rnd(void)
{
    s_rng ^= s_rng << 13;
    s_rng ^= s_rng >> 17;
    s_rng ^= s_rng << 5;
    return s_rng;
}

/* Granlund & Montgomery's condition for M = ceil(2^(32+s)/d) to give
 * floor(n/d) = (n x M) >> (32+s) for every uint32 n: M d - 2^(32+s) <= 2^s. */
static void test_reciprocals_are_exact_for_all_uint32(void **state)
{
    (void)state;
    static const struct {
        uint32_t m, d, s;
    } c[] = {
        {KM_FIXDIV_M10, 10u, 3u},
        {KM_FIXDIV_M1000, 1000u, 6u},
        {KM_FIXDIV_M5, 5u, 2u},
        {KM_FIXDIV_M100, 100u, 6u},
    };
    for (unsigned i = 0; i < sizeof c / sizeof c[0]; i++) {
        const uint64_t p = (uint64_t)1 << (32u + c[i].s);
        assert_int_equal(c[i].m, (uint32_t)((p + c[i].d - 1u) / c[i].d)); /* the ceiling */
        const uint64_t e = (uint64_t)c[i].m * c[i].d - p;
        assert_true(e <= ((uint64_t)1 << c[i].s));
    }
}

static void test_umulhi_matches_64_bit_product(void **state)
{
    (void)state;
    static const uint32_t edge[] = {0u,          1u,          0xFFFFu,       0x10000u,       0x7FFFFFFFu,
                                    0x80000000u, 0xFFFFFFFFu, KM_FIXDIV_M10, KM_FIXDIV_M1000};
    for (unsigned i = 0; i < sizeof edge / sizeof edge[0]; i++) {
        for (unsigned j = 0; j < sizeof edge / sizeof edge[0]; j++) {
            assert_int_equal(km_umulhi(edge[i], edge[j]), (uint32_t)(((uint64_t)edge[i] * edge[j]) >> 32));
        }
    }
    for (unsigned k = 0; k < 2000000u; k++) {
        const uint32_t a = rnd(), b = rnd();
        assert_int_equal(km_umulhi(a, b), (uint32_t)(((uint64_t)a * b) >> 32));
    }
}

static void check_sdiv(int32_t n)
{
    if (km_sdiv10(n) != n / 10 || km_sdiv100(n) != n / 100 || km_sdiv1000(n) != n / 1000 ||
        km_sdiv2560(n) != n / 2560 || km_sdiv256000(n) != n / 256000) {
        fail_msg("n = %d: %d %d %d %d %d", n, km_sdiv10(n), km_sdiv100(n), km_sdiv1000(n), km_sdiv2560(n),
                 km_sdiv256000(n));
    }
}

/* The unsigned quotients over random uint32 and the top of the range. */
static void test_unsigned_quotients_match_c(void **state)
{
    (void)state;
    for (unsigned k = 0; k < 2000000u; k++) {
        const uint32_t n = k < 1000u ? 0xFFFFFFFFu - k : rnd();
        assert_int_equal(km_udiv10(n), n / 10u);
        assert_int_equal(km_udiv100(n), n / 100u);
        assert_int_equal(km_udiv1000(n), n / 1000u);
        assert_int_equal(km_udiv2560(n), n / 2560u);
        assert_int_equal(km_udiv256000(n), n / 256000u);
    }
}

/* Every n within +-2^22 (past every operand of the tick but the integrator
 * and the profile's speeds), the edges of int32 and around each multiple
 * of the divisors there, and random n over all of int32. */
static void test_signed_quotients_match_c(void **state)
{
    (void)state;
    for (int32_t n = -(1 << 22); n <= (1 << 22); n++) {
        check_sdiv(n);
    }
    check_sdiv(INT32_MIN);
    check_sdiv(INT32_MIN + 1);
    check_sdiv(INT32_MAX);
    check_sdiv(INT32_MAX - 1);
    static const int32_t d[] = {10, 100, 1000, 2560, 256000};
    for (unsigned i = 0; i < sizeof d / sizeof d[0]; i++) {
        for (int32_t q = INT32_MAX / d[i] - 3; q <= INT32_MAX / d[i]; q++) {
            for (int32_t r = -1; r <= 1; r++) {
                check_sdiv(q * d[i] + r);
                check_sdiv(-q * d[i] - r);
            }
        }
    }
    for (unsigned k = 0; k < 2000000u; k++) {
        check_sdiv((int32_t)rnd());
    }
}

/* ---- the profile as it was (divisions, 64-bit square root) ------------- */

static int32_t ref_abs(int32_t v)
{
    return v < 0 ? -v : v;
}

static uint32_t ref_isqrt64(uint64_t x)
{
    uint64_t r = 0;
    uint64_t bit = (uint64_t)1 << 62;
    while (bit > x) {
        bit >>= 2;
    }
    while (bit != 0u) {
        if (x >= r + bit) {
            x -= r + bit;
            r = (r >> 1) + bit;
        } else {
            r >>= 1;
        }
        bit >>= 2;
    }
    return (uint32_t)r;
}

static void ref_advance(km_profile_t *p, uint32_t dt_us)
{
    const int32_t q = p->vel / 1000, r = p->vel % 1000;
    const int32_t qd = q * (int32_t)dt_us;
    p->pos += qd / 1000;
    p->pos_rem += (qd % 1000) * 1000 + r * (int32_t)dt_us;
    p->pos += p->pos_rem / 1000000;
    p->pos_rem %= 1000000;
}

/* One step of a stream speed's two low passes (km_profile.c's prv_smooth). */
static int32_t ref_smooth(int32_t v, int32_t to)
{
    const int32_t n = 1 << KM_PROFILE_STREAM_SMOOTH_SHIFT;
    return v + ((to - v) / n != 0 ? (to - v) / n : to - v);
}

/* The stream interpolator's piece (km_profile.h) with C's divisions. */
static void ref_stream_piece(km_profile_t *p, uint32_t dt_us)
{
    const int32_t ahead = p->s_lag - p->s_since;
    if (ahead <= 0) {
        const int32_t left = p->target - p->pos;
        if (left == 0 || (left > 0) != (p->vel > 0)) {
            p->pos = p->target;
            p->pos_rem = 0;
            p->vel = 0;
            p->vel_rem = 0;
            p->done = true;
            return;
        }
        p->stream = false;
        p->accel = p->accel < 1000000 / KM_PROFILE_STREAM_ACCEL_DIV ? p->accel * KM_PROFILE_STREAM_ACCEL_DIV
                                                                    : 1000000;
        const uint64_t vsq = (uint64_t)(uint32_t)p->vmax * (uint32_t)p->vmax;
        p->vsq_hi = (uint32_t)(vsq >> 32);
        p->vsq_lo = (uint32_t)vsq;
        return;
    }
    int32_t ref = p->target, vff = 0;
    if (ahead > 0) {
        vff = p->s_vel;
        ref -= (vff / 1000) * (ahead / 1000);
    }
    const int32_t emax = p->vmax / 32 + 1;
    int32_t err = ref - p->pos;
    err = err > emax ? emax : (err < -emax ? -emax : err);
    const int32_t near = KM_PROFILE_STREAM_NEAR_U;
    int32_t corr = err * 8;
    if (err > near || err < -near) {
        corr = (err > 0 ? near : -near) * 8 + (err > 0 ? err - near : err + near) * 16;
    }
    int32_t want = vff + corr;
    want = want > p->vmax ? p->vmax : (want < -p->vmax ? -p->vmax : want);
    int32_t dv = p->accel * (int32_t)dt_us + p->vel_rem;
    p->vel_rem = dv % 1000;
    dv /= 1000;
    if (p->s_vr < want) {
        p->s_vr = p->s_vr + dv < want ? p->s_vr + dv : want;
    } else if (p->s_vr > want) {
        p->s_vr = p->s_vr - dv > want ? p->s_vr - dv : want;
    }
    p->s_vf = ref_smooth(p->s_vf, p->s_vr);
    p->vel = ref_smooth(p->vel, p->s_vf);
    ref_advance(p, dt_us);
    const int32_t left = p->target - p->pos;
    if (left == 0 && p->vel == 0) {
        p->pos = p->target;
        p->pos_rem = 0;
        p->vel = 0;
        p->vel_rem = 0;
        p->done = true;
    }
}

static void ref_piece(km_profile_t *p, uint32_t dt_us)
{
    if (p->s_period > 0 && p->s_since < 4000000) {
        p->s_since += (int32_t)dt_us;
    }
    const int32_t e = p->target - p->pos;
    if (p->stream) {
        ref_stream_piece(p, dt_us);
        return;
    }
    int32_t dv = p->accel * (int32_t)dt_us + p->vel_rem;
    p->vel_rem = dv % 1000;
    dv /= 1000;
    int32_t d = ref_abs(e) - ref_abs(p->vel / 1000) * (int32_t)dt_us / 1000;
    if (d < 0) {
        d = 0;
    }
    const uint64_t two_a_d = 2u * (uint64_t)(uint32_t)p->accel * 1000u * (uint64_t)(uint32_t)d;
    int32_t vb = (int32_t)ref_isqrt64(two_a_d);
    if (vb > p->vmax) {
        vb = p->vmax;
    }
    const int32_t want = e >= 0 ? vb : -vb;
    if (p->vel < want) {
        p->vel = p->vel + dv < want ? p->vel + dv : want;
    } else if (p->vel > want) {
        p->vel = p->vel - dv > want ? p->vel - dv : want;
    }
    ref_advance(p, dt_us);
    const int32_t left = p->target - p->pos;
    if (left == 0 || ((left > 0) != (e > 0) && e != 0) ||
        (ref_abs(left) <= ref_abs(p->vel) / 1000 + 1 && ref_abs(p->vel) <= dv)) {
        p->pos = p->target;
        p->pos_rem = 0;
        p->vel = 0;
        p->vel_rem = 0;
        p->done = true;
    }
}

static bool ref_step(km_profile_t *p, uint32_t dt_us)
{
    while (!p->done && dt_us > 0u) {
        const uint32_t piece = dt_us > 2000u ? 2000u : dt_us; /* km_profile.c's STEP_MAX_US */
        ref_piece(p, piece);
        dt_us -= piece;
    }
    return p->done;
}

static void expect_same(const km_profile_t *a, const km_profile_t *b, unsigned run, unsigned tick)
{
    if (a->pos != b->pos || a->vel != b->vel || a->pos_rem != b->pos_rem || a->vel_rem != b->vel_rem ||
        a->done != b->done) {
        fail_msg("run %u tick %u: pos %d/%d vel %d/%d rem %d/%d vrem %d/%d done %d/%d", run, tick, a->pos,
                 b->pos, a->vel, b->vel, a->pos_rem, b->pos_rem, a->vel_rem, b->vel_rem, a->done, b->done);
    }
    assert_int_equal(km_profile_vel_ddps(a), b->vel / 1000);
}

/* Random moves (speed, time, stream segments, a new command mid-move) at
 * 1 ms ticks and at odd tick lengths (pieces below 1 ms and up to 2 ms,
 * several pieces a tick), speeds from 1 u/s to past 2^28 u/s (the 64-bit
 * root's range) and up to 2^30 u/s (the bound of a 2 ms piece):
 * the rewritten profile equals the old one at every tick. */
static void test_profile_equals_division_reference(void **state)
{
    (void)state;
    static const uint32_t dts[] = {1000u, 1000u, 1000u, 250u, 999u, 1001u, 2500u, 17u, 2000u, 4999u};
    for (unsigned run = 0; run < 1200u; run++) {
        km_profile_t a, b;
        const int32_t from = (int32_t)(rnd() % 20001u) - 10000;
        km_profile_reset(&a, from);
        b = a;
        const uint32_t dt = dts[run % (sizeof dts / sizeof dts[0])];
        for (unsigned cmd = 0; cmd < 3u; cmd++) {
            const int32_t to = (int32_t)(rnd() % 40001u) - 20000;
            const uint32_t big = rnd() % 8u == 0u;
            const int32_t vmax = big ? (int32_t)(rnd() % 1200000000u) + 1 : (int32_t)(rnd() % 7200000u) + 1;
            const int32_t accel = (int32_t)(rnd() % (big ? 1000000u : 200000u)) + 1;
            switch (rnd() % 3u) {
            case 0:
                km_profile_move(&a, to, vmax, accel);
                km_profile_move(&b, to, vmax, accel);
                break;
            case 1: {
                const uint32_t ms = rnd() % 3000u + 1u;
                km_profile_move_time(&a, to, ms, vmax);
                km_profile_move_time(&b, to, ms, vmax);
                break;
            }
            default: {
                const uint32_t us = rnd() % 40000u + 1u;
                km_profile_stream(&a, to, us, vmax, accel);
                km_profile_stream(&b, to, us, vmax, accel);
                break;
            }
            }
            expect_same(&a, &b, run, 0);
            const unsigned ticks = cmd < 2u ? rnd() % 400u : 20000u;
            for (unsigned t = 1; t <= ticks; t++) {
                const bool da = km_profile_step(&a, dt), db = ref_step(&b, dt);
                assert_int_equal(da, db);
                expect_same(&a, &b, run, t);
                if (da) {
                    break;
                }
            }
        }
    }
}

/* km_isqrt (the profile's braking and retime roots, motor mode's approach
 * speed) is floor(sqrt) for every value below 2^62: around every square
 * of a 32-bit root's magnitudes, all of uint32, and random 62-bit values. */
static void test_isqrt_matches_64_bit_root(void **state)
{
    (void)state;
    for (uint32_t b = 0; b < 31u; b++) {
        for (uint32_t k = 0; k < 64u; k++) {
            const uint64_t r = ((uint64_t)1 << b) + k * (((uint64_t)1 << b) / 64u + 1u);
            for (int d = -1; d <= 1; d++) {
                const uint64_t x = r * r + (uint64_t)(int64_t)d;
                if (r >= ((uint64_t)1 << 31) || x >= ((uint64_t)1 << 62)) {
                    continue;
                }
                assert_int_equal(km_isqrt((uint32_t)(x >> 32), (uint32_t)x), ref_isqrt64(x));
            }
        }
    }
    for (unsigned k = 0; k < 1000000u; k++) {
        const uint32_t n = rnd() >> (rnd() % 32u);
        assert_int_equal(km_isqrt(0u, n), ref_isqrt64(n));
        const uint64_t x = (((uint64_t)rnd() << 32) | rnd()) >> (2u + rnd() % 62u);
        assert_int_equal(km_isqrt((uint32_t)(x >> 32), (uint32_t)x), ref_isqrt64(x));
    }
    assert_int_equal(km_isqrt(0u, 0xFFFFFFFFu), 65535u);
    assert_int_equal(km_isqrt(0x3FFFFFFFu, 0xFFFFFFFFu), ref_isqrt64(((uint64_t)1 << 62) - 1u));
}

#if !KM_CONTROL_COMPACT
/* km_isqrt56_fast (the fast build's braking root, its low word's steps
 * written out) is floor(sqrt) for every value below 2^56: around every
 * square of a root below 2^28, and random values of every length. */
static void test_isqrt56_fast_matches_64_bit_root(void **state)
{
    (void)state;
    for (uint32_t b = 0; b < 28u; b++) {
        for (uint32_t k = 0; k < 256u; k++) {
            const uint64_t r = ((uint64_t)1 << b) + k * (((uint64_t)1 << b) / 256u + 1u);
            for (int d = -1; d <= 1; d++) {
                const uint64_t x = r * r + (uint64_t)(int64_t)d;
                if (x >= ((uint64_t)1 << 56)) {
                    continue;
                }
                assert_int_equal(km_isqrt56_fast((uint32_t)(x >> 32), (uint32_t)x), ref_isqrt64(x));
            }
        }
    }
    for (unsigned k = 0; k < 1000000u; k++) {
        const uint64_t x = (((uint64_t)rnd() << 32) | rnd()) >> (8u + rnd() % 56u);
        assert_int_equal(km_isqrt56_fast((uint32_t)(x >> 32), (uint32_t)x), ref_isqrt64(x));
    }
    assert_int_equal(km_isqrt56_fast(0xFFFFFFu, 0xFFFFFFFFu), ref_isqrt64(((uint64_t)1 << 56) - 1u));
}

/* km_rsqrt_top8 holds what its comment defines: [i] is the integer
 * nearest 2^31 / sqrt(N), N = (64 + i + 1/2) 2^24 = (129 + 2i) 2^23, i.e.
 * (2z - 1)^2 (129 + 2i) < 2^41 < (2z + 1)^2 (129 + 2i), in integers. */
static void test_rsqrt_table_is_its_formula(void **state)
{
    (void)state;
    for (uint32_t i = 0; i < 192u; i++) {
        const uint64_t z = km_rsqrt_top8[i], n = 129u + 2u * i, two41 = (uint64_t)1 << 41;
        assert_true((2u * z - 1u) * (2u * z - 1u) * n < two41);
        assert_true((2u * z + 1u) * (2u * z + 1u) * n > two41);
    }
}

/* km_isqrt56_fast's root of the normalised top word (2^30 .. 2^32) is
 * floor(sqrt) at both ends of every root's range: y = s^2 - 1, s^2 and
 * s^2 + 2s for every s in 2^15 .. 2^16. */
static void test_isqrt32_top_every_square_boundary(void **state)
{
    (void)state;
    uint32_t z;
    for (uint32_t s = 1u << 15; s < (1u << 16); s++) {
        const uint32_t sq = s * s;
        if (s > (1u << 15)) {
            assert_int_equal(km_isqrt32_top(sq - 1u, &z), s - 1u);
        }
        assert_int_equal(km_isqrt32_top(sq, &z), s);
        assert_int_equal(km_isqrt32_top(sq + 2u * s, &z), s);
    }
    assert_int_equal(km_isqrt32_top(0xFFFFFFFFu, &z), 65535u);
}

/* km_isqrt56_fast (table, Newton steps, +-1 against the square) equals the
 * nibble root km_isqrt56 at n^2 - 1 and n^2: every n below 2^16, and at
 * every root length from 17 to 28 bits the first and last 4,096 roots and
 * 65,536 spread over the length; then 4 million values of random length. */
static void test_isqrt56_fast_equals_nibble_root_at_every_boundary(void **state)
{
    (void)state;
    for (uint64_t n = 1; n < ((uint64_t)1 << 28); n++) {
        const uint32_t b = n < 2u ? 1u : 32u - (uint32_t)__builtin_clz((uint32_t)n), lo_end = 1u << (b - 1u);
        if (n >= 0x10000u && n >= lo_end + 4096u && n + 4096u < 2u * (uint64_t)lo_end &&
            (n & ((lo_end >> 16) - 1u)) != 0u) {
            continue;
        }
        for (uint64_t x = n * n - 1u; x <= n * n; x++) {
            const uint32_t hi = (uint32_t)(x >> 32), lo = (uint32_t)x;
            assert_int_equal(km_isqrt56_fast(hi, lo), km_isqrt56(hi, lo));
        }
    }
    for (unsigned k = 0; k < 4000000u; k++) {
        const uint64_t x = (((uint64_t)rnd() << 32) | rnd()) >> (8u + rnd() % 56u);
        const uint32_t hi = (uint32_t)(x >> 32), lo = (uint32_t)x;
        assert_int_equal(km_isqrt56_fast(hi, lo), km_isqrt56(hi, lo));
    }
    assert_int_equal(km_isqrt56_fast(0u, 0u), 0u);
    assert_int_equal(km_isqrt56_fast(0xFFFFFFu, 0xFFFFFFFFu), 0xFFFFFFFu);
}
#endif

/* Long moves (up to 80,000 deg) at speeds from 2^28 to 2^30 u/s and hard
 * accelerations: their braking roots are of values from 2^56 up, the root
 * taken from a shifted one and stepped up; equal to the 64-bit root at
 * every tick. */
static void test_profile_fast_long_moves_equal_reference(void **state)
{
    (void)state;
    static const uint32_t dts[] = {1000u, 2000u, 1500u, 999u};
    for (unsigned run = 0; run < 300u; run++) {
        km_profile_t a, b;
        km_profile_reset(&a, 0);
        b = a;
        const int32_t to = (int32_t)(rnd() % 1600001u) - 800000;
        const int32_t vmax = (int32_t)(rnd() % 0x30000000u) + 0x10000000;
        const int32_t accel = (int32_t)(rnd() % 500000u) + 500000;
        km_profile_move(&a, to, vmax, accel);
        km_profile_move(&b, to, vmax, accel);
        const uint32_t dt = dts[run % 4u];
        for (unsigned t = 1; t <= 100000u; t++) {
            const bool da = km_profile_step(&a, dt), db = ref_step(&b, dt);
            assert_int_equal(da, db);
            expect_same(&a, &b, run, t);
            if (da) {
                break;
            }
        }
        assert_true(a.done);
    }
}

/* The cruise speed of a retimed move as it was computed, in 64 bits
 * (km_profile.c's prv_retime_cruise before the two-word rewrite). */
static int32_t ref_retime_cruise(int32_t v0, int32_t dm, int32_t t, int32_t a)
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
    const int64_t b = (int64_t)v0 + (int64_t)a * t;
    const int64_t c = (int64_t)a * dm + ((int64_t)v0 * v0) / 2;
    const int64_t disc = b * b - 4 * c;
    if (b <= 0 || disc < 0) {
        return (int32_t)ref_isqrt64((uint64_t)c);
    }
    return (int32_t)((b - (int64_t)ref_isqrt64((uint64_t)disc)) / 2);
}

/* A speed from 1 to 2^30 u/s, about evenly spread over its binary magnitudes. */
static int32_t rnd_speed(void)
{
    const int32_t v = (int32_t)((rnd() & 0x3FFFFFFFu) >> (rnd() % 30u));
    return v > 0 ? v : 1;
}

/* km_profile_retime (docs/protocol.md §5.4 0x65 retargeting a moving
 * servo) sets the cruise speed the 64-bit formula gave, for speeds up to
 * 2^30 u/s, either direction, times past 65,535 ms and accelerations
 * past the bound: the two-word arithmetic and root equal it exactly. */
static void test_retime_cruise_equals_64_bit_reference(void **state)
{
    (void)state;
    for (unsigned run = 0; run < 400000u; run++) {
        km_profile_t p;
        km_profile_reset(&p, 0);
        p.done = false;
        p.vel = rnd() % 2u ? rnd_speed() : -rnd_speed();
        const int32_t to = (int32_t)(rnd() % 2001u) - 1000; /* |d| <= 1e6 u: a retime, not a new move */
        const uint32_t time_ms = rnd() % 70000u + 1u;
        const int32_t accel = (int32_t)(rnd() % 1200000u) + 1000;
        const int32_t vlimit = rnd_speed();
        km_profile_retime(&p, to, time_ms, vlimit, accel);
        const int32_t d = to * KM_PROFILE_U_PER_DDEG;
        const int32_t a = (accel < 1000000 ? accel : 1000000) / 1000;
        const int32_t v0 = (d >= 0 ? p.vel : -p.vel) / 1000;
        int32_t vc = ref_retime_cruise(v0, d < 0 ? -d : d, time_ms > 65535u ? 65535 : (int32_t)time_ms, a);
        const int32_t vlim = vlimit / 1000;
        vc = vc < 1 ? 1 : (vc > vlim ? vlim : vc);
        const int32_t want = vc * 1000 > 1 ? vc * 1000 : 1;
        if (p.vmax != want) {
            fail_msg("run %u: vel %d to %d in %u ms at %d, limit %d: vmax %d, reference %d", run, p.vel, to,
                     time_ms, accel, vlimit, p.vmax, want);
        }
    }
}

/* floor(n / d) for the divisor that wanders (the speed estimators' span
 * and window): equal to C's `/` for every d up to 40,000 (both nominal
 * bands of 7,000 and 20,000 us, their edges and the power-of-two
 * brackets between), at the largest n and at n = q x d +- 1, and for
 * random n and d over the whole domain (d < 2^30), for the nominal values
 * the estimators use and the smallest and largest allowed; d = 0 gives 0. */
static const km_recip_near_t s_near[] = {KM_RECIP_NEAR(7000u), KM_RECIP_NEAR(20000u), KM_RECIP_NEAR(256u),
                                         KM_RECIP_NEAR(65536u)};

static void check_udiv_near(uint32_t n, uint32_t d, unsigned c)
{
    const uint32_t want = n / d;
    const uint32_t got = km_udiv_near(n, d, &s_near[c]);
    if (got != want) {
        fail_msg("km_udiv_near(%u, %u, d0 %u) = %u, C says %u", n, d, s_near[c].d0, got, want);
    }
}

static void test_udiv_near_matches_c(void **state)
{
    (void)state;
    for (unsigned d0 = 0; d0 < sizeof s_near / sizeof s_near[0]; d0++) {
        for (uint32_t d = 1u; d <= 40000u; d++) {
            const uint32_t n = rnd();
            check_udiv_near(0xFFFFFFFFu, d, d0);
            check_udiv_near(2000000000u, d, d0);
            check_udiv_near(n, d, d0);
            check_udiv_near(d - 1u, d, d0);
            check_udiv_near((n / d) * d, d, d0);
            if ((n / d) * d != 0u) {
                check_udiv_near((n / d) * d - 1u, d, d0);
            }
        }
        for (uint32_t d = s_near[d0].d0 / 2u; d <= s_near[d0].d0 * 2u; d += 1u + s_near[d0].d0 / 65536u) {
            check_udiv_near(0xFFFFFFFFu, d, d0);
            check_udiv_near(rnd(), d, d0);
        }
        assert_int_equal(km_udiv_near(12345u, 0u, &s_near[d0]), 0u);
    }
    for (unsigned i = 0; i < 1000000u; i++) {
        const uint32_t d = (rnd() >> (2u + rnd() % 30u)) | 1u; /* every magnitude below 2^30 */
        check_udiv_near(rnd(), d, i % 4u);
        check_udiv_near(rnd() >> (rnd() % 32u), d, (i + 1u) % 4u);
    }
}

/* ---- the fast speed estimate as it was (the span summed every tick) ---- */

static int32_t ref_fast_step(km_speed_fast_t *f, int32_t position, uint32_t dt_us)
{
    if (dt_us > 100000u) {
        dt_us = 100000u;
    }
    f->head = (uint8_t)((f->head + 1u) % KM_SPEED_FAST_N);
    f->pos[f->head] = position;
    f->dt[f->head] = dt_us;
    if (f->count < KM_SPEED_FAST_N) {
        f->count++;
    }
    uint32_t span = 0;
    uint8_t i = f->head;
    for (uint8_t k = 1; k < f->count; k++) {
        span += f->dt[i];
        i = (uint8_t)((i + KM_SPEED_FAST_N - 1u) % KM_SPEED_FAST_N);
    }
    f->span_us = span;
    int32_t d = position - f->pos[i];
    d = d > 2000 ? 2000 : (d < -2000 ? -2000 : d);
    f->ddps = span ? (d * 1000000) / (int32_t)span : 0;
    return f->ddps;
}

/* The running span equals the summed one from init and from a zeroed
 * ring, with ticks of any length (stalled ones included). */
/* The 1 kHz fast path (span 7000 us, a reciprocal of 7) equals the
 * division for every displacement the estimator lets through. */
static void test_speed_fast_steady_tick_every_displacement(void **state)
{
    (void)state;
    for (int32_t d = -2100; d <= 2100; d++) {
        km_speed_fast_t a, b;
        km_speed_fast_init(&a, 0);
        b = a;
        for (unsigned t = 1; t <= KM_SPEED_FAST_N + 2u; t++) {
            const int32_t pos = d * (int32_t)t / (int32_t)(KM_SPEED_FAST_N - 1u);
            assert_int_equal(km_speed_fast_step(&a, pos, 1000u), ref_fast_step(&b, pos, 1000u));
        }
        assert_int_equal(a.span_us, 7000u);
    }
}

/* Spans off 7,000 us (a tick of another length still in the ring:
 * control/km_speed_est.c's general division, km_udiv_near) give C's
 * quotient for every displacement. */
static void test_speed_fast_other_span_every_displacement(void **state)
{
    (void)state;
    for (int32_t s = -20; s <= 20; s++) {
        for (int32_t d = -2000; d <= 2000; d++) {
            km_speed_fast_t f;
            km_speed_fast_init(&f, 0);
            for (unsigned t = 1; t < KM_SPEED_FAST_N - 1u; t++) {
                (void)km_speed_fast_step(&f, 0, 1000u);
            }
            const int32_t v = km_speed_fast_step(&f, d, (uint32_t)(1000 + s));
            assert_int_equal(f.span_us, (uint32_t)(7000 + s));
            assert_int_equal(v, d * 1000000 / (7000 + s));
        }
    }
}

static void test_speed_fast_running_span_equals_sum(void **state)
{
    (void)state;
    for (unsigned run = 0; run < 200u; run++) {
        km_speed_fast_t a, b;
        int32_t pos = (int32_t)(rnd() % 2001u) - 1000;
        if (run % 2u) {
            km_speed_fast_init(&a, pos);
        } else {
            memset(&a, 0, sizeof a);
        }
        b = a;
        for (unsigned t = 0; t < 500u; t++) {
            pos += (int32_t)(rnd() % 61u) - 30;
            const uint32_t r = rnd() % 16u;
            const uint32_t dt = r < 12u ? 1000u : (r < 15u ? rnd() % 3000u : rnd() % 300000u);
            assert_int_equal(km_speed_fast_step(&a, pos, dt), ref_fast_step(&b, pos, dt));
            assert_int_equal(a.span_us, b.span_us);
        }
    }
}

/* The reported speed (0x47) as it was: a division every window. */
static int32_t ref_window_step(km_speed_window_t *w, int32_t position, uint32_t dt_us)
{
    if (w->have_position) {
        w->acc += position - w->last_position;
        w->us += dt_us;
        if (w->us >= KM_SPEED_WINDOW_US) {
            const int32_t acc = w->acc > 20000 ? 20000 : (w->acc < -20000 ? -20000 : w->acc);
            w->dps = (acc * 100000) / (int32_t)w->us;
            w->acc = 0;
            w->us = 0;
        }
    }
    w->last_position = position;
    w->have_position = true;
    return w->dps;
}

/* Its exact 20 ms window (x 5) equals the division, for 1 ms ticks and
 * any others, over displacements past the clamp. */
static void test_speed_window_equals_division(void **state)
{
    (void)state;
    for (unsigned run = 0; run < 400u; run++) {
        km_speed_window_t a, b;
        km_speed_window_init(&a);
        b = a;
        int32_t pos = 0;
        const int32_t step = (int32_t)(rnd() % 4001u) - 2000;
        for (unsigned t = 0; t < 300u; t++) {
            pos += step + (int32_t)(rnd() % 7u) - 3;
            const uint32_t dt = run % 2u ? 1000u : (rnd() % 4u ? 1000u : rnd() % 5000u);
            assert_int_equal(km_speed_window_step(&a, pos, dt), ref_window_step(&b, pos, dt));
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reciprocals_are_exact_for_all_uint32),
        cmocka_unit_test(test_umulhi_matches_64_bit_product),
        cmocka_unit_test(test_unsigned_quotients_match_c),
        cmocka_unit_test(test_signed_quotients_match_c),
        cmocka_unit_test(test_profile_equals_division_reference),
        cmocka_unit_test(test_isqrt_matches_64_bit_root),
        cmocka_unit_test(test_profile_fast_long_moves_equal_reference),
        cmocka_unit_test(test_retime_cruise_equals_64_bit_reference),
        cmocka_unit_test(test_udiv_near_matches_c),
        cmocka_unit_test(test_speed_fast_steady_tick_every_displacement),
        cmocka_unit_test(test_speed_fast_other_span_every_displacement),
#if !KM_CONTROL_COMPACT
        cmocka_unit_test(test_isqrt56_fast_matches_64_bit_root),
        cmocka_unit_test(test_rsqrt_table_is_its_formula),
        cmocka_unit_test(test_isqrt32_top_every_square_boundary),
        cmocka_unit_test(test_isqrt56_fast_equals_nibble_root_at_every_boundary),
#endif
        cmocka_unit_test(test_speed_fast_running_span_equals_sum),
        cmocka_unit_test(test_speed_window_equals_division),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
