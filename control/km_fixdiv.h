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

/* High 32 bits of a x b, exact, from four 16 x 16 products. */
static inline __attribute__((always_inline)) uint32_t km_umulhi(uint32_t a, uint32_t b)
{
    const uint32_t ah = a >> 16, al = a & 0xFFFFu, bh = b >> 16, bl = b & 0xFFFFu;
    const uint32_t ll = al * bl;
    const uint32_t m1 = ah * bl + (ll >> 16);     /* < 2^32: (2^16-1)^2 + 2^16 */
    const uint32_t m2 = al * bh + (m1 & 0xFFFFu); /* likewise */
    return ah * bh + (m1 >> 16) + (m2 >> 16);
}

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

/* Four bits of the radicand, two of the root: one step (KM_SQRT_NIBBLES's
 * body); 32-bit for roots below 2^28 (docs/control-design.md "Arithmetic"). */
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

/* floor(sqrt(hi:lo)) for hi:lo < 2^56, leading zero nibbles skipped
 * (the profile's braking speed calls it directly outside the compact build). */
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
    KM_SQRT_NIBBLES(hi, n)
    KM_SQRT_NIBBLES(lo, m)
    return root;
}

#if !KM_CONTROL_COMPACT
/* km_isqrt56 with the low word's eight steps written out (no loop counter:
 * the profile's braking speed, every braking tick, in the fast build); a
 * low word's leading zero nibbles are stepped through (root and rest stay
 * 0), which bounds the tick's cost below 2^32 too. */
static inline uint32_t km_isqrt56_fast(uint32_t hi, uint32_t lo)
{
    uint32_t root = 0, rem = 0;
    if (hi != 0u) {
        unsigned n = 8u; /* nibbles left in hi */
        while ((hi >> 24) == 0u) {
            hi <<= 8;
            n -= 2u;
        }
        while ((hi >> 28) == 0u) {
            hi <<= 4;
            n--;
        }
        KM_SQRT_NIBBLES(hi, n)
    }
    KM_SQRT_NIBBLE(lo);
    KM_SQRT_NIBBLE(lo);
    KM_SQRT_NIBBLE(lo);
    KM_SQRT_NIBBLE(lo);
    KM_SQRT_NIBBLE(lo);
    KM_SQRT_NIBBLE(lo);
    KM_SQRT_NIBBLE(lo);
    KM_SQRT_NIBBLE(lo);
    return root;
}
#endif

/* floor(sqrt(hi:lo)) for hi:lo < 2^62, 32-bit operations only
 * (docs/control-design.md "Arithmetic"). */
uint32_t km_isqrt(uint32_t hi, uint32_t lo);

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
    return v > m ? m : (v < -m ? -m : v);
}
#endif

#endif
