/* Division by the control tick's constants without a divide instruction:
 * reciprocal multiplies, exact (km_fixdiv.h says why;
 * tests/unit/test_control_fixdiv.c checks it). */
#include "km_fixdiv.h"

#define PRV_INLINE static inline __attribute__((always_inline))

/* Each returns 0 at once below its divisor: the tick's many small
 * operands (a shaft holding still) then cost a compare. */
PRV_INLINE uint32_t prv_udiv10(uint32_t n)
{
    return n < 10u ? 0u : km_umulhi(n, KM_FIXDIV_M10) >> 3;
}

PRV_INLINE uint32_t prv_udiv100(uint32_t n)
{
    return n < 100u ? 0u : km_umulhi(n, KM_FIXDIV_M100) >> 6;
}

PRV_INLINE uint32_t prv_udiv1000(uint32_t n)
{
    return n < 1000u ? 0u : km_umulhi(n, KM_FIXDIV_M1000) >> 6;
}

/* 2560 = 2^9 x 5: floor(floor(n / 2^9) / 5) = floor(n / 2560). */
PRV_INLINE uint32_t prv_udiv2560(uint32_t n)
{
    return n < 2560u ? 0u : km_umulhi(n >> 9, KM_FIXDIV_M5) >> 2;
}

/* 256000 = 2^8 x 1000, likewise. */
PRV_INLINE uint32_t prv_udiv256000(uint32_t n)
{
    return prv_udiv1000(n >> 8);
}

/* Each unsigned one, and its signed twin: truncated toward zero like C's
 * `/` (the magnitude of INT32_MIN is formed in uint32). */
#define PRV_DIVS(d)                                              \
    uint32_t km_udiv##d(uint32_t n)                              \
    {                                                            \
        return prv_udiv##d(n);                                   \
    }                                                            \
    int32_t km_sdiv##d(int32_t n)                                \
    {                                                            \
        const uint32_t q = prv_udiv##d(n < 0 ? 0u - (uint32_t)n : (uint32_t)n); \
        return n < 0 ? -(int32_t)q : (int32_t)q;                 \
    }

PRV_DIVS(10)
PRV_DIVS(100)
PRV_DIVS(1000)
PRV_DIVS(2560)
PRV_DIVS(256000)
