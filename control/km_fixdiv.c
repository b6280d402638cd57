/* SPDX-License-Identifier: Apache-2.0 */
/* Division by the tick's constants: reciprocal multiplies (km_fixdiv.h). */
#include "km_fixdiv.h"

#if KM_CONTROL_COMPACT
/* (n x m) >> (32 + s): the one km_umulhi (flash). */
static inline uint32_t prv_mulhi_shr(uint32_t n, uint32_t m, uint32_t s)
{
    return km_umulhi(n, m) >> s;
}

/* (n x m) >> (32 + s) for a tick's divisor: two of the four products below
 * 2^16 (most of the tick's dividends), else the one km_umulhi. */
static inline uint32_t prv_div_mulhi_shr(uint32_t n, uint32_t m, uint32_t s)
{
    if (n <= 0xFFFFu) {
        return ((n * (m >> 16) + ((n * (m & 0xFFFFu)) >> 16)) >> 16) >> s;
    }
    return km_umulhi(n, m) >> s;
}
#else
/* (n x m) >> (32 + s): one copy of the multiply for every divisor (flash). */
static __attribute__((noinline)) uint32_t prv_mulhi_shr(uint32_t n, uint32_t m, uint32_t s)
{
    if (n <= 0xFFFFu) { /* two of the four products */
        return ((n * (m >> 16) + ((n * (m & 0xFFFFu)) >> 16)) >> 16) >> s;
    }
    return km_umulhi(n, m) >> s;
}
#endif

#if KM_CONTROL_COMPACT
/* A divisor of the tick: floor(n / d) = floor((n >> pre) / d') with
 * d' = d / 2^pre, its reciprocal m and shift s (km_fixdiv.h). */
typedef struct {
    uint32_t m;
    uint16_t d;
    uint8_t pre, s;
} prv_divisor_t;

enum { PRV_D10, PRV_D100, PRV_D1000, PRV_D2560, PRV_D256000 };

/* 2560 = 2^9 x 5 and 256000 = 2^8 x 1000: floor(floor(n / 2^k) / d') = floor(n / d). */
static const prv_divisor_t s_divisors[] = {
    [PRV_D10] = {KM_FIXDIV_M10, 10u, 0u, 3u},         [PRV_D100] = {KM_FIXDIV_M100, 100u, 0u, 6u},
    [PRV_D1000] = {KM_FIXDIV_M1000, 1000u, 0u, 6u},   [PRV_D2560] = {KM_FIXDIV_M5, 5u, 9u, 2u},
    [PRV_D256000] = {KM_FIXDIV_M1000, 1000u, 8u, 6u},
};

/* floor(n / d) for divisor `k`, 0 at once below d (a compare, not a multiply). */
static __attribute__((noinline)) uint32_t prv_udiv(uint32_t n, unsigned k)
{
    const prv_divisor_t *v = &s_divisors[k];
    n >>= v->pre;
    return n < v->d ? 0u : prv_div_mulhi_shr(n, v->m, v->s);
}

/* n / d toward zero, as C's `/`, for divisor `k`. */
static __attribute__((noinline)) int32_t prv_sdiv(int32_t n, unsigned k)
{
    const uint32_t q = prv_udiv(n < 0 ? 0u - (uint32_t)n : (uint32_t)n, k);
    return n < 0 ? -(int32_t)q : (int32_t)q;
}

/* Each unsigned quotient and its signed twin. */
#define PRV_DIVS(d)                   \
    uint32_t km_udiv##d(uint32_t n)   \
    {                                 \
        return prv_udiv(n, PRV_D##d); \
    }                                 \
    int32_t km_sdiv##d(int32_t n)     \
    {                                 \
        return prv_sdiv(n, PRV_D##d); \
    }

#else

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
#endif

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

#if KM_CONTROL_COMPACT
__attribute__((noinline)) uint32_t km_umulhi(uint32_t a, uint32_t b)
{
    return km_umulhi_inline(a, b);
}

__attribute__((noinline)) int32_t km_clamp(int32_t v, int32_t lo, int32_t hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

__attribute__((noinline)) int32_t km_sat(int32_t v, int32_t m)
{
    return km_sat_inline(v, m);
}
#endif

/* floor(sqrt(hi:lo)) for hi:lo < 2^62: the nibble root of hi:lo / 2^8
 * times 16 is at most 15 below the root (docs/control-design.md "Arithmetic"). */
uint32_t km_isqrt(uint32_t hi, uint32_t lo)
{
    if (hi < (1u << 24)) {
        return km_isqrt56(hi, lo);
    }
    uint32_t r = km_isqrt56(hi >> 8, (lo >> 8) | (hi << 24)) << 4;
    for (;;) {
        const uint32_t n = r + 1u, sq_hi = km_umulhi(n, n);
        if (sq_hi > hi || (sq_hi == hi && n * n > lo)) {
            return r;
        }
        r = n;
    }
}

#if !KM_CONTROL_COMPACT
/* 1/sqrt from a value's top 8 bits (km_isqrt56_fast's first guess). */
const uint16_t km_rsqrt_top8[192] = {
    65281u, 64781u, 64292u, 63814u, 63347u, 62889u, 62442u, 62004u, 61575u, 61154u, 60742u, 60339u, 59943u,
    59555u, 59175u, 58801u, 58435u, 58075u, 57722u, 57376u, 57035u, 56700u, 56372u, 56049u, 55731u, 55419u,
    55112u, 54810u, 54513u, 54221u, 53933u, 53650u, 53371u, 53097u, 52826u, 52560u, 52298u, 52040u, 51785u,
    51535u, 51288u, 51044u, 50804u, 50567u, 50333u, 50103u, 49876u, 49652u, 49430u, 49212u, 48997u, 48784u,
    48574u, 48367u, 48163u, 47961u, 47761u, 47564u, 47370u, 47178u, 46988u, 46800u, 46615u, 46432u, 46251u,
    46072u, 45895u, 45720u, 45547u, 45376u, 45207u, 45040u, 44875u, 44711u, 44550u, 44390u, 44232u, 44075u,
    43920u, 43767u, 43615u, 43465u, 43316u, 43169u, 43024u, 42879u, 42737u, 42595u, 42456u, 42317u, 42180u,
    42044u, 41910u, 41776u, 41644u, 41514u, 41384u, 41256u, 41129u, 41003u, 40878u, 40754u, 40631u, 40510u,
    40390u, 40270u, 40152u, 40035u, 39919u, 39803u, 39689u, 39576u, 39464u, 39352u, 39242u, 39133u, 39024u,
    38916u, 38810u, 38704u, 38599u, 38494u, 38391u, 38289u, 38187u, 38086u, 37986u, 37887u, 37788u, 37690u,
    37593u, 37497u, 37401u, 37307u, 37213u, 37119u, 37027u, 36935u, 36843u, 36753u, 36663u, 36573u, 36485u,
    36397u, 36309u, 36222u, 36136u, 36051u, 35966u, 35882u, 35798u, 35715u, 35632u, 35550u, 35469u, 35388u,
    35307u, 35228u, 35148u, 35070u, 34991u, 34914u, 34837u, 34760u, 34684u, 34608u, 34533u, 34458u, 34384u,
    34310u, 34237u, 34164u, 34092u, 34020u, 33949u, 33878u, 33807u, 33737u, 33668u, 33599u, 33530u, 33461u,
    33393u, 33326u, 33259u, 33192u, 33126u, 33060u, 32994u, 32929u, 32864u, 32800u,
};
#endif
