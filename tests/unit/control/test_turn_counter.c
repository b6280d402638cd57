/* SPDX-License-Identifier: Apache-2.0 */
/* control/km_turn_counter.c: multi-turn position from a single-turn
 * absolute encoder (docs/protocol.md §5.3 0x46 as i32, §6 encoder products). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_turn_counter.h"

#define COUNTS 4096u

/* Raw counts of an angle in 0.1 deg (any sign, any number of turns). */
static uint16_t raw_of(int32_t ddeg)
{
    int32_t m = ddeg % 3600;
    if (m < 0) {
        m += 3600;
    }
    return (uint16_t)(((uint32_t)m * COUNTS + 1800u) / 3600u % COUNTS);
}

/* §6: at boot the position is the angle within one turn, [0, 360.0) deg. */
static void test_s6_boot_reads_angle_within_one_turn(void **state)
{
    (void)state;
    km_turn_counter_t t;
    km_turn_counter_init(&t, COUNTS, raw_of(3700)); /* the shaft at 370.0 deg */
    assert_int_equal(km_turn_counter_update(&t, raw_of(3700)), 100);
    km_turn_counter_init(&t, COUNTS, raw_of(-100)); /* at -10.0 deg = 350.0 */
    assert_int_equal(km_turn_counter_update(&t, raw_of(-100)), 3500);
    km_turn_counter_init(&t, COUNTS, 0);
    assert_int_equal(km_turn_counter_update(&t, 0), 0);
}

/* §5.3 0x46 multi-turn: turning forward 10 turns and back 25 in 0.4 deg
 * steps (400 deg/s at 1 kHz) is followed to within the encoder's
 * resolution (0.088 deg: 1 in 0.1 deg units). */
static void test_s5_3_follows_many_turns_both_ways(void **state)
{
    (void)state;
    km_turn_counter_t t;
    km_turn_counter_init(&t, COUNTS, 0);
    int32_t x = 0;
    for (int i = 0; i < 9000; i++) {
        x += 4;
        const int32_t p = km_turn_counter_update(&t, raw_of(x));
        assert_true(p - x <= 1 && x - p <= 1);
    }
    assert_int_equal(t.turns, 10);
    for (int i = 0; i < 22500; i++) {
        x -= 4;
        const int32_t p = km_turn_counter_update(&t, raw_of(x));
        assert_true(p - x <= 1 && x - p <= 1);
    }
    assert_int_equal(x, -54000);
    assert_int_equal(t.turns, -15);
}

/* Just under half a turn per reading is still counted the right way; a
 * reading exactly at the wrap point (raw 0 after counts - 1) is one step. */
static void test_steps_up_to_half_a_turn(void **state)
{
    (void)state;
    km_turn_counter_t t;
    km_turn_counter_init(&t, COUNTS, COUNTS - 1u);
    assert_int_equal(km_turn_counter_update(&t, 0), 3600);
    km_turn_counter_init(&t, COUNTS, 0);
    assert_int_equal(km_turn_counter_update(&t, COUNTS - 1u), -1); /* -0.088 deg */
    km_turn_counter_init(&t, COUNTS, 100);
    int32_t p = km_turn_counter_update(&t, (uint16_t)(100u + COUNTS / 2u - 1u));
    assert_int_equal(t.turns, 0);
    p = km_turn_counter_update(&t, 100); /* and back */
    assert_int_equal(t.turns, 0);
    assert_int_equal(p, (100 * 3600 + 2048) / 4096);
}

/* Bad input has a defined outcome: a raw value out of range is taken
 * modulo the counts; counts below 2 are made 2. */
static void test_bad_input_defined(void **state)
{
    (void)state;
    km_turn_counter_t t;
    km_turn_counter_init(&t, COUNTS, (uint16_t)(COUNTS + 10u));
    assert_int_equal(t.last, 10);
    assert_int_equal(km_turn_counter_update(&t, (uint16_t)(COUNTS + 10u)), (10 * 3600 + 2048) / 4096);
    km_turn_counter_init(&t, 0, 5);
    assert_int_equal(t.counts, 2);
    assert_true(t.last < 2u);
}

/* The int32 wrap of 0x46 is defined (no signed overflow): near +596,523
 * turns the position goes on through the wrap. */
static void test_s5_3_wraps_like_i32(void **state)
{
    (void)state;
    km_turn_counter_t t;
    km_turn_counter_init(&t, COUNTS, 0);
    t.turns = INT32_MAX / 3600; /* 596,523 turns: 2,147,482,800 */
    const int32_t a = km_turn_counter_update(&t, 0);
    assert_int_equal(a, 2147482800);
    const int32_t b = km_turn_counter_update(&t, 2048); /* + 180.0 deg */
    assert_int_equal((int32_t)((uint32_t)b - (uint32_t)a), 1800);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s6_boot_reads_angle_within_one_turn),
        cmocka_unit_test(test_s5_3_follows_many_turns_both_ways),
        cmocka_unit_test(test_steps_up_to_half_a_turn),
        cmocka_unit_test(test_bad_input_defined),
        cmocka_unit_test(test_s5_3_wraps_like_i32),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
