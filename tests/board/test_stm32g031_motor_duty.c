/* SPDX-License-Identifier: Apache-2.0 */
/* The STM32G031 bridge's compare value (motor_duty.h): the multiply and
 * shift against the exact quotient, every magnitude the drive takes. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "motor_duty.h"

static void test_every_magnitude_exact(void **state)
{
    (void)state;
    for (uint32_t mag = 0u; mag <= (uint32_t)KM_MOTOR_PWM_MAX; mag++) {
        assert_int_equal(km_motor_duty(mag), mag * KM_MOTOR_PWM_PERIOD / (uint32_t)KM_MOTOR_PWM_MAX);
    }
}

static void test_full_drive_is_the_period(void **state)
{
    (void)state;
    assert_int_equal(km_motor_duty((uint32_t)KM_MOTOR_PWM_MAX), KM_MOTOR_PWM_PERIOD);
    assert_int_equal(km_motor_duty(0u), 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_magnitude_exact),
        cmocka_unit_test(test_full_drive_is_the_period),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
