/* SPDX-License-Identifier: Apache-2.0 */
/* USART1 divider at the G031's 64 MHz: every baud the protocol allows
 * (register 0x10 x 100, products 9600..1000000) is within 2 %, and rates
 * that cannot be made are refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "usart_brr.h"

#define FCK 64000000u

static void test_common_rates_exact_enough(void **state)
{
    (void)state;
    assert_int_equal(km_usart_brr(FCK, 1000000u), 64u);
    assert_int_equal(km_usart_brr(FCK, 115200u), 556u);
    assert_int_equal(km_usart_brr(FCK, 9600u), 6667u);
}

static void test_every_step_of_100_within_2_percent(void **state)
{
    (void)state;
    for (uint32_t baud = 9600u; baud <= 1000000u; baud += 100u) {
        uint32_t brr = km_usart_brr(FCK, baud);
        assert_true(brr >= 16u);
        uint32_t actual = FCK / brr;
        uint32_t diff = actual > baud ? actual - baud : baud - actual;
        assert_true(diff * 50u <= baud);
    }
}

static void test_out_of_reach_refused(void **state)
{
    (void)state;
    assert_int_equal(km_usart_brr(FCK, 0u), 0u);
    assert_int_equal(km_usart_brr(FCK, 5000000u), 0u); /* BRR < 16 */
    assert_int_equal(km_usart_brr(FCK, 900u), 0u);     /* BRR > 16 bits */
    /* 3.7 Mbaud: BRR 17 gives 3.765 M, 1.8 % off: still accepted. */
    assert_int_not_equal(km_usart_brr(FCK, 3700000u), 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_common_rates_exact_enough),
        cmocka_unit_test(test_every_step_of_100_within_2_percent),
        cmocka_unit_test(test_out_of_reach_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
