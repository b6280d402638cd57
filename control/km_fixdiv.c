/* SPDX-License-Identifier: Apache-2.0 */
/* Division by the tick's constants: reciprocal multiplies (km_fixdiv.h). */
#include "km_fixdiv.h"

/* (n x m) >> (32 + s): one copy of the multiply for every divisor (flash). */
static __attribute__((noinline)) uint32_t prv_mulhi_shr(uint32_t n, uint32_t m, uint32_t s)
{
    if (n <= 0xFFFFu) { /* two of the four products */
        return ((n * (m >> 16) + ((n * (m & 0xFFFFu)) >> 16)) >> 16) >> s;
    }
    return km_umulhi(n, m) >> s;
}

#define PRV_INLINE static inline __attribute__((always_inline))

/* floor(n / d), 0 at once below d (a compare, not a call). */
PRV_INLINE uint32_t prv_udiv(uint32_t n, uint32_t d, uint32_t m, uint32_t s)
{
    return n < d ? 0u : prv_mulhi_shr(n, m, s);
}

PRV_INLINE uint32_t prv_udiv10(uint32_t n)
{
    return prv_udiv(n, 10u, KM_FIXDIV_M10, 3u);
}

PRV_INLINE uint32_t prv_udiv100(uint32_t n)
{
    return prv_udiv(n, 100u, KM_FIXDIV_M100, 6u);
}

PRV_INLINE uint32_t prv_udiv1000(uint32_t n)
{
    return prv_udiv(n, 1000u, KM_FIXDIV_M1000, 6u);
}

/* 2560 = 2^9 x 5: floor(floor(n / 2^9) / 5) = floor(n / 2560). */
PRV_INLINE uint32_t prv_udiv2560(uint32_t n)
{
    return prv_udiv(n >> 9, 5u, KM_FIXDIV_M5, 2u);
}

/* 256000 = 2^8 x 1000, likewise. */
PRV_INLINE uint32_t prv_udiv256000(uint32_t n)
{
    return prv_udiv(n >> 8, 1000u, KM_FIXDIV_M1000, 6u);
}

/* Each unsigned quotient and its signed twin (toward zero, as C's `/`). */
#define PRV_DIVS(d)                                                             \
    uint32_t km_udiv##d(uint32_t n)                                             \
    {                                                                           \
        return prv_udiv##d(n);                                                  \
    }                                                                           \
    int32_t km_sdiv##d(int32_t n)                                               \
    {                                                                           \
        const uint32_t q = prv_udiv##d(n < 0 ? 0u - (uint32_t)n : (uint32_t)n); \
        return n < 0 ? -(int32_t)q : (int32_t)q;                                \
    }

PRV_DIVS(10)
PRV_DIVS(100)
PRV_DIVS(1000)
PRV_DIVS(2560)
PRV_DIVS(256000)

/* A reciprocal in (floor(2^32 / d) / 2, floor(2^32 / d)], d >= 2: the
 * tangent at d0 less one near d0, else 2^31 >> k for 2^k <= d < 2^(k+1). */
static uint32_t prv_recip_seed(uint32_t d, const km_recip_near_t *c)
{
    const uint32_t lo = c->d0 - c->d0 / 4u;
    if (d - lo < lo) { /* d0 x 3/4 <= d < d0 x 3/2 */
        const int32_t delta = (int32_t)d - (int32_t)c->d0;
        return c->r0 - (uint32_t)((delta * (int32_t)c->slope) >> 8) - 1u;
    }
    uint32_t seed = 0x80000000u;
    for (uint32_t top = d >> 1; top != 0u; top >>= 1) {
        seed >>= 1;
    }
    return seed;
}

/* floor(n / d): Newton's iteration to floor(2^32 / d), then one correction. */
__attribute__((noinline)) uint32_t km_udiv_near(uint32_t n, uint32_t d, const km_recip_near_t *c)
{
    if (n < d) {
        return 0u; /* a shaft holding still: no reciprocal */
    }
    if (d < 2u) {
        return d == 1u ? n : 0u;
    }
    uint32_t r = prv_recip_seed(d, c);
    uint32_t e = 0u - d * r; /* 2^32 - d r: r never passes 2^32 / d */
    for (unsigned k = 0; k < 6u && e >= 4u * d; k++) {
        r += prv_mulhi_shr(r, e, 0u); /* Newton: the error squared */
        e = 0u - d * r;
    }
    while (e >= d) { /* r = floor(2^32 / d) */
        r++;
        e -= d;
    }
    uint32_t q = km_umulhi(n, r); /* floor(n / d) or one less: n r / 2^32 > n / d - 1 */
    if (n - q * d >= d) {
        q++;
    }
    return q;
}
