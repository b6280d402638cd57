/* SPDX-License-Identifier: Apache-2.0 */
/* The compact run-time routines (boards/stm32g031/boot/boot_rt.c: the
 * bootloader's, and the 32 KiB build's application's with
 * KM_G031_COMPACT_RT, docs/footprint.md) against C's own operators and
 * string functions on the host: division and remainder, signed and
 * unsigned, over edge and pseudo-random operands; division by zero gives
 * its documented values; memmove both ways over overlapping ranges,
 * memcpy, memset, memcmp's sign. The file is included with its string
 * functions renamed, so the host's own stay in use. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#define memcpy rt_memcpy
#define memmove rt_memmove
#define memset rt_memset
#define memcmp rt_memcmp
#include "boot/boot_rt.c"
#undef memcpy
#undef memmove
#undef memset
#undef memcmp

static uint32_t s_x = 0x9E3779B9u;

/* xorshift32: operands of every size (shifted by a random amount). */
static uint32_t prv_rand(void)
{
    s_x ^= s_x << 13;
    s_x ^= s_x >> 17;
    s_x ^= s_x << 5;
    return s_x >> (s_x & 31u);
}

static void prv_check_unsigned(uint32_t n, uint32_t d)
{
    const uint64_t qr = __aeabi_uidivmod(n, d);
    assert_int_equal((uint32_t)qr, n / d);
    assert_int_equal((uint32_t)(qr >> 32), n % d);
    assert_int_equal(__aeabi_uidiv(n, d), n / d);
}

static void prv_check_signed(int32_t n, int32_t d)
{
    if (n == INT32_MIN && d == -1) {
        return; /* C leaves it undefined; checked on its own below */
    }
    const uint64_t qr = __aeabi_idivmod(n, d);
    assert_int_equal((int32_t)(uint32_t)qr, n / d);
    assert_int_equal((int32_t)(uint32_t)(qr >> 32), n % d);
    assert_int_equal(__aeabi_idiv(n, d), n / d);
}

/* Division as C divides: edge operands and 200,000 pseudo-random pairs. */
static void test_division_matches_c(void **state)
{
    (void)state;
    static const uint32_t k_edge[] = {1u,          2u,          3u,          7u,         10u,
                                      100u,        255u,        65535u,      65536u,     0x7FFFFFFFu,
                                      0x80000000u, 0x80000001u, 0xFFFFFFFEu, 0xFFFFFFFFu};
    for (size_t i = 0; i < sizeof k_edge / sizeof k_edge[0]; i++) {
        for (size_t j = 0; j < sizeof k_edge / sizeof k_edge[0]; j++) {
            prv_check_unsigned(k_edge[i], k_edge[j]);
            prv_check_signed((int32_t)k_edge[i], (int32_t)k_edge[j]);
        }
        prv_check_unsigned(0u, k_edge[i]);
        prv_check_signed(0, (int32_t)k_edge[i]);
    }
    for (unsigned k = 0; k < 200000u; k++) {
        const uint32_t n = prv_rand();
        const uint32_t d = prv_rand() | 1u;
        prv_check_unsigned(n, d);
        prv_check_signed((int32_t)n, (int32_t)d);
    }
    /* INT32_MIN / -1 wraps to INT32_MIN, remainder 0, as libgcc's. */
    const uint64_t qr = __aeabi_idivmod(INT32_MIN, -1);
    assert_int_equal((uint32_t)qr, 0x80000000u);
    assert_int_equal((uint32_t)(qr >> 32), 0u);
}

/* Division by zero: quotient 0xFFFFFFFF unsigned, -1 (dividend >= 0) or
 * 1 (below 0) signed, the remainder the dividend; no trap. */
static void test_division_by_zero_is_defined(void **state)
{
    (void)state;
    assert_int_equal(__aeabi_uidiv(1234u, 0u), 0xFFFFFFFFu);
    assert_int_equal((uint32_t)(__aeabi_uidivmod(1234u, 0u) >> 32), 1234u);
    assert_int_equal(__aeabi_idiv(1234, 0), -1);
    assert_int_equal(__aeabi_idiv(0, 0), -1);
    assert_int_equal(__aeabi_idiv(-1234, 0), 1);
    assert_int_equal((int32_t)(uint32_t)(__aeabi_idivmod(-1234, 0) >> 32), -1234);
}

/* memmove over overlapping ranges both ways, memcpy, memset, memcmp. */
static void test_string_routines(void **state)
{
    (void)state;
    uint8_t a[64];
    uint8_t want[64];
    for (unsigned shift = 1; shift < 20u; shift++) {
        for (unsigned i = 0; i < sizeof a; i++) {
            a[i] = (uint8_t)i;
            want[i] = (uint8_t)i;
        }
        memmove(want + shift, want, 40u);
        assert_ptr_equal(rt_memmove(a + shift, a, 40u), a + shift);
        assert_memory_equal(a, want, sizeof a);
        memmove(want, want + shift, 40u);
        rt_memmove(a, a + shift, 40u);
        assert_memory_equal(a, want, sizeof a);
    }
    uint8_t b[64];
    assert_ptr_equal(rt_memcpy(b, a, sizeof a), b);
    assert_memory_equal(b, a, sizeof a);
    assert_ptr_equal(rt_memset(b + 3, 0x1A5, 7u), b + 3);
    for (unsigned i = 0; i < sizeof b; i++) {
        assert_int_equal(b[i], i >= 3u && i < 10u ? 0xA5u : a[i]);
    }
    assert_int_equal(rt_memcmp(a, a, sizeof a), 0);
    b[5] = 0x01u;
    b[6] = 0xFFu;
    assert_true(rt_memcmp(b + 5, b + 6, 1u) < 0);
    assert_true(rt_memcmp(b + 6, b + 5, 1u) > 0);
    assert_int_equal(rt_memcmp(b, a, 0u), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_division_matches_c),
        cmocka_unit_test(test_division_by_zero_is_defined),
        cmocka_unit_test(test_string_routines),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
