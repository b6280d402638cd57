/* SPDX-License-Identifier: Apache-2.0 */
/* Division by the tick's constants without a divide instruction (the M0
 * has none): floor(n / d) = (n x M) >> (32 + s), M = ceil(2^(32+s) / d),
 * exact for every uint32 n (docs/control-design.md "Division without a
 * divide"; tests/unit/control/test_control_fixdiv.c). */
#ifndef KM_FIXDIV_H
#define KM_FIXDIV_H

#include <stdint.h>

/* 1 in the 32 KiB STM32G031F6 build (boards/stm32g031/board.cmake): the
 * forms that spend tick instructions to save flash (docs/footprint.md
 * "control/ in the 32 KiB build (2026-11-27, branch f6ctl)"); 0 keeps the
 * faster ones. Same results. */
#ifndef KM_CONTROL_COMPACT
#define KM_CONTROL_COMPACT 0
#endif

/* A step of the control tick or of a request kept a call in the compact
 * build: LTO makes the tick one function, and these calls spill fewer
 * registers and need fewer long branches than their bodies inlined
 * (flash); inlined otherwise (instructions). docs/footprint.md. */
#if KM_CONTROL_COMPACT
#define KM_COMPACT_NOINLINE __attribute__((noinline))
#else
#define KM_COMPACT_NOINLINE
#endif

/* High 32 bits of a x b, exact, from four 16 x 16 products. */
static inline __attribute__((always_inline)) uint32_t km_umulhi_inline(uint32_t a, uint32_t b)
{
    const uint32_t ah = a >> 16, al = a & 0xFFFFu, bh = b >> 16, bl = b & 0xFFFFu;
    const uint32_t ll = al * bl;
    const uint32_t m1 = ah * bl + (ll >> 16);     /* < 2^32: (2^16-1)^2 + 2^16 */
    const uint32_t m2 = al * bh + (m1 & 0xFFFFu); /* likewise */
    return ah * bh + (m1 >> 16) + (m2 >> 16);
}

#if KM_CONTROL_COMPACT
/* High 32 bits of a x b: km_umulhi_inline, one copy, not inlined (flash). */
uint32_t km_umulhi(uint32_t a, uint32_t b);
#else
/* High 32 bits of a x b: km_umulhi_inline at each use (tick instructions). */
static inline __attribute__((always_inline)) uint32_t km_umulhi(uint32_t a, uint32_t b)
{
    return km_umulhi_inline(a, b);
}
#endif

/* The reciprocals: M = ceil(2^(32+s) / d). */
#define KM_FIXDIV_M10 0xCCCCCCCDu   /* d = 10, s = 3 */
#define KM_FIXDIV_M1000 0x10624DD3u /* d = 1000, s = 6 */
#define KM_FIXDIV_M5 0xCCCCCCCDu    /* d = 5, s = 2 */
#define KM_FIXDIV_M100 0xA3D70A3Eu  /* d = 100, s = 6 */

/* Quotients of uint32 (floor) and int32 (toward zero, as C's `/`). */
uint32_t km_udiv10(uint32_t n);
uint32_t km_udiv100(uint32_t n);
uint32_t km_udiv1000(uint32_t n);
uint32_t km_udiv2560(uint32_t n);
uint32_t km_udiv256000(uint32_t n);
int32_t km_sdiv10(int32_t n);
int32_t km_sdiv100(int32_t n);
int32_t km_sdiv1000(int32_t n);
int32_t km_sdiv2560(int32_t n);
int32_t km_sdiv256000(int32_t n);

/* floor(n / d) for d < 2^30 (0 for d = 0) by multiplies only, d wandering
 * around a nominal d0 (docs/control-design.md "Division without a divide"). */
typedef struct {
    uint32_t d0;    /* the nominal divisor, 256 .. 65536 */
    uint32_t r0;    /* floor(2^32 / d0) */
    uint32_t slope; /* ceil(2^40 / d0^2): r0 / d0 in 1/256 */
} km_recip_near_t;
#define KM_RECIP_NEAR(d0)                                                        \
    {                                                                            \
        (uint32_t)(d0), (uint32_t)(0x100000000ull / (uint64_t)(d0)),             \
            (uint32_t)((0x10000000000ull + (uint64_t)(d0) * (uint64_t)(d0)-1u) / \
                       ((uint64_t)(d0) * (uint64_t)(d0)))                        \
    }
uint32_t km_udiv_near(uint32_t n, uint32_t d, const km_recip_near_t *c);

/* Four bits of the radicand, two of the root: one step of km_isqrt56;
 * 32-bit for roots below 2^28 (docs/control-design.md "Arithmetic"). */
#define KM_SQRT_NIBBLE(w)                                   \
    do {                                                    \
        const uint32_t x = (rem << 4) | ((w) >> 28);        \
        (w) <<= 4;                                          \
        const uint32_t r8 = root << 3, t2 = (r8 << 1) + 4u; \
        root <<= 2;                                         \
        if (x >= t2) {                                      \
            const uint32_t t3 = t2 + r8 + 5u;               \
            if (x >= t3) {                                  \
                rem = x - t3;                               \
                root |= 3u;                                 \
            } else {                                        \
                rem = x - t2;                               \
                root |= 2u;                                 \
            }                                               \
        } else if (x > r8) {                                \
            rem = x - (r8 + 1u);                            \
            root |= 1u;                                     \
        } else {                                            \
            rem = x;                                        \
        }                                                   \
    } while (0)

/* n steps of KM_SQRT_NIBBLE on the word w. */
#define KM_SQRT_NIBBLES(w, n) \
    for (; (n) > 0u; (n)--) { \
        KM_SQRT_NIBBLE(w);    \
    }

/* floor(sqrt(hi:lo)) for hi:lo < 2^56, leading zero nibbles skipped: the
 * nibbles of hi, then those of lo (two copies of the step: instructions;
 * the compact build runs its one copy twice). */
static inline uint32_t km_isqrt56(uint32_t hi, uint32_t lo)
{
    uint32_t root = 0, rem = 0;
    unsigned n = 8u, m = 8u; /* nibbles left in hi, in lo */
    if (hi == 0u) {
        hi = lo;
        m = 0u;
        if (hi == 0u) {
            return 0u;
        }
    }
    while ((hi >> 24) == 0u) {
        hi <<= 8;
        n -= 2u;
    }
    while ((hi >> 28) == 0u) {
        hi <<= 4;
        n--;
    }
#if KM_CONTROL_COMPACT
    for (;;) {
        KM_SQRT_NIBBLES(hi, n)
        if (m == 0u) {
            return root;
        }
        hi = lo;
        n = m;
        m = 0u;
    }
#else
    KM_SQRT_NIBBLES(hi, n)
    KM_SQRT_NIBBLES(lo, m)
    return root;
#endif
}

#if !KM_CONTROL_COMPACT
/* 1/sqrt from a value's top 8 bits: [i] = round(2^31 / sqrt((64 + i + 1/2)
 * x 2^24)) (docs/control-design.md "Arithmetic"). */
extern const uint16_t km_rsqrt_top8[192];

/* floor(sqrt(y)) for 2^30 <= y < 2^32 from the table's 1/sqrt z: s0 = y z,
 * one step s0 + (y - s0^2) z / 2, then at most one step up; z back in *z_out. */
static inline __attribute__((always_inline)) uint32_t km_isqrt32_top(uint32_t y, uint32_t *z_out)
{
    const uint32_t z = km_rsqrt_top8[(y >> 24) - 64u];
    uint32_t s = ((y >> 16) * z) >> 15;
    const int32_t rest0 = (int32_t)(y - s * s);
    s = (uint32_t)((int32_t)s + (((rest0 >> 10) * (int32_t)z) >> 22));
    while (y - s * s > 2u * s) {
        s++;
    }
    *z_out = z;
    return s;
}

/* floor(sqrt(hi:lo)) for hi:lo < 2^56 (the profile's braking speed, every
 * braking tick, in the fast build): the root s of the normalised top 32
 * bits, then the low root bits d = (x - s^2 4^m) / (2 s 2^m) by the
 * reciprocal 2^31 / s (one Newton step from the table), then +-1 against
 * the square (docs/control-design.md "Arithmetic"). */
static inline uint32_t km_isqrt56_fast(uint32_t hi, uint32_t lo)
{
    uint32_t y = hi == 0u ? lo : hi, sh = 0, z;
    if (y == 0u) {
        return 0u;
    }
    if ((y >> 16) == 0u) {
        y <<= 16;
        sh = 16u;
    }
    if ((y >> 24) == 0u) {
        y <<= 8;
        sh += 8u;
    }
    if ((y >> 28) == 0u) {
        y <<= 4;
        sh += 4u;
    }
    if ((y >> 30) == 0u) {
        y <<= 2;
        sh += 2u;
    }
    if (hi == 0u) {
        return km_isqrt32_top(y, &z) >> (sh >> 1);
    }
    const uint32_t s = km_isqrt32_top(y | (lo >> (32u - sh)), &z); /* sh >= 8 */
    const uint32_t k = sh >> 1, m = 16u - k, sq_hi = (s * s) >> sh, sq_lo = (s * s) << (32u - sh);
    const uint32_t e_lo = lo - sq_lo, e_hi = hi - sq_hi - (lo < sq_lo ? 1u : 0u);
    const uint32_t e_top = (e_hi << (k + 1u)) | (e_lo >> (31u - k)); /* e / 2^(m + 15) */
    const int32_t w_err = (int32_t)((1u << 31) - s * z);
    const uint32_t w = z + (uint32_t)(((w_err >> 8) * (int32_t)z) >> 23); /* 2^31 / s */
    const uint32_t d = (e_top * w) >> 17;
    uint32_t r = (s << m) + d;
    int32_t rest = (int32_t)(e_lo - ((s * d) << (m + 1u)) - d * d); /* x - r^2 */
    while (rest < 0) {
        r--;
        rest += (int32_t)(2u * r + 1u);
    }
    while ((uint32_t)rest > 2u * r) {
        r++;
        rest -= (int32_t)(2u * r - 1u);
    }
    return r;
}
#endif

/* floor(sqrt(hi:lo)) for hi:lo < 2^62, 32-bit operations only
 * (docs/control-design.md "Arithmetic"). */
uint32_t km_isqrt(uint32_t hi, uint32_t lo);

/* v bounded to +-m: m above m, else -m below -m; inlined in every build
 * (the position loop's saturations, the tick's hottest calls). */
static inline int32_t km_sat_inline(int32_t v, int32_t m)
{
    return v > m ? m : (v < -m ? -m : v);
}

#if KM_CONTROL_COMPACT
/* v bounded to [lo, hi]: lo below lo, else hi above hi (one copy, not inlined: flash). */
int32_t km_clamp(int32_t v, int32_t lo, int32_t hi);
/* v bounded to +-m: m above m, else -m below -m. */
int32_t km_sat(int32_t v, int32_t m);
#else
/* v bounded to [lo, hi]: lo below lo, else hi above hi (inlined: tick instructions). */
static inline int32_t km_clamp(int32_t v, int32_t lo, int32_t hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

/* v bounded to +-m: m above m, else -m below -m. */
static inline int32_t km_sat(int32_t v, int32_t m)
{
    return km_sat_inline(v, m);
}
#endif

#endif
