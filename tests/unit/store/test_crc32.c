/* SPDX-License-Identifier: Apache-2.0 */
/* km_crc32 (firmware/store/km_crc32.c) against zlib's CRC-32: the check
 * value, an empty run, a long buffer, and a CRC continued across calls.
 * Built twice: the nibble-table km_crc32 (test_crc32) and the bitwise one
 * of the 32 KiB STM32G031F6's application store (test_crc32_bitwise,
 * KM_CRC32_BITWISE=1), so both give the same CRC. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_crc32.h"

#define PRV_LEN 1000u

/* A fixed pseudo-random buffer (zlib.crc32 of it: 0x5B8F28CE). */
static void prv_fill(uint8_t *buf)
{
    for (uint32_t i = 0; i < PRV_LEN; i++) {
        buf[i] = (uint8_t)((i * 2654435761u) >> 13);
    }
}

/* The standard check value: CRC-32 of "123456789" is 0xCBF43926. */
static void test_check_value(void **state)
{
    (void)state;
    static const uint8_t k_digits[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    assert_int_equal(km_crc32(0u, k_digits, 9u), 0xCBF43926u);
    assert_int_equal(km_crc32(0u, k_digits, 0u), 0u);
}

/* A long buffer, whole and continued across two calls (zlib's figures). */
static void test_long_and_continued(void **state)
{
    (void)state;
    uint8_t buf[PRV_LEN];
    prv_fill(buf);
    assert_int_equal(km_crc32(0u, buf, PRV_LEN), 0x5B8F28CEu);
    const uint32_t head = km_crc32(0u, buf, 333u);
    assert_int_equal(head, 0xB84C78F4u);
    assert_int_equal(km_crc32(head, buf + 333, PRV_LEN - 333u), 0x5B8F28CEu);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_check_value),
        cmocka_unit_test(test_long_and_continued),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
