/* SPDX-License-Identifier: Apache-2.0 */
/* Division by the tick's constants: reciprocal multiplies (km_fixdiv.h). */
#include "km_fixdiv.h"

/* (n x m) >> (32 + s): one copy of the multiply for every divisor (flash). */
static __attribute__((noinline)) uint32_t prv_mulhi_shr(uint32_t n, uint32_t m, uint32_t s)
{
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
