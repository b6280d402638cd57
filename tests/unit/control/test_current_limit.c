/* SPDX-License-Identifier: Apache-2.0 */
/* §5.4 0x5C (bounded by §5.1 0x14): the current limit, on its own and
 * against the plant through the control tick. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_current_limit.h"
#include "km_plant_rig.h"

/* The cap closes while the current is over the limit, opens below it,
 * stays in 0..1000; limit 0 = none. */
static void test_cap_integrates_and_saturates(void **state)
{
    (void)state;
    km_current_limit_t l;
    km_current_limit_init(&l);
    assert_int_equal(km_current_limit_step(&l, 500, 2000), 1000);
    assert_int_equal(km_current_limit_step(&l, -2800, 2000), 900); /* either sign: 800 over / 8 */
    for (int i = 0; i < 100; i++) {
        (void)km_current_limit_step(&l, 5000, 2000);
    }
    assert_int_equal(l.cap, 0);
    assert_int_equal(km_current_limit_step(&l, 0, 2000), 250);
    assert_int_equal(km_current_limit_step(&l, 9000, 0), 1000); /* no limit */
}

/* A shaft held against a load above the stall torque (3 N.m, the motor
 * stalls at ~2 N.m): with 0x5C = 1200 mA the current settles at the limit
 * (within 5 %) instead of the ~2.5 A stall current; with the limit at the
 * product's 2000 mA it settles near 2000 mA. */
static void test_s5_4_0x5C_holds_a_stalled_shaft_at_the_limit(void **state)
{
    (void)state;
    const uint16_t limits[] = {1200, 2000};
    for (size_t k = 0; k < 2; k++) {
        kr_rig_t r;
        kr_init(&r);
        r.params.current_limit_ma = limits[k];
        assert_true(kr_torque(&r, 2));
        r.in.ext_torque_unm = -3000000;
        kr_run(&r, 1000);
        int32_t peak = 0;
        int32_t sum = 0;
        for (int i = 0; i < 200; i++) {
            kr_tick(&r);
            const int32_t i_ma = r.live.current < 0 ? -r.live.current : r.live.current;
            peak = i_ma > peak ? i_ma : peak;
            sum += i_ma;
        }
        const int32_t mean = sum / 200;
        print_message("0x5C %u mA: mean %d mA, peak %d mA over 200 ms held against 3 N.m\n", limits[k], mean,
                      peak);
        assert_true(mean <= limits[k] * 105 / 100 && mean >= limits[k] * 90 / 100);
        assert_true(peak <= limits[k] * 110 / 100);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cap_integrates_and_saturates),
        cmocka_unit_test(test_s5_4_0x5C_holds_a_stalled_shaft_at_the_limit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
