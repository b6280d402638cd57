/* SPDX-License-Identifier: Apache-2.0 */
/* control/km_protect.c on its own, without the plant: docs/protocol.md §5.2
 * (0x32 enable, 0x33 release mode, 0x34 action, 0x36 flags and clear,
 * 0x3C-0x3F thresholds and times) and §4 status bits 0-3, at 1 ms ticks
 * with inputs as functions of time (no plant, no control tick). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_protect.h"

#define TICK_US 1000u

static km_control_params_t params(void)
{
    km_control_params_t p;
    memset(&p, 0, sizeof p);
    p.prot_enable = 0x0F;
    p.prot_release = 0x00;
    p.prot_state = 0x54; /* the default: stall, temperature, current brake (01); voltage free (00) */
    p.voltage_high_v = 9;
    p.voltage_low_v = 6;
    p.temp_trip_c = 60;
    p.temp_hysteresis_c = 5;
    p.current_trip_ma = 1500;
    p.current_time_100ms = 20;
    p.stall_pwm = 600;
    p.stall_time_100ms = 20;
    return p;
}

static km_protect_in_t nominal(void)
{
    km_protect_in_t in;
    memset(&in, 0, sizeof in);
    in.voltage_mv = 7400;
    in.current_ma = 200;
    in.temperature_c10 = 300;
    in.servo_mode = true;
    return in;
}

/* Runs `ms` ticks of `in`; returns the first ms (1-based, from this call)
 * at which `bit` tripped, or 0. */
static uint32_t run(km_protect_t *s, const km_protect_in_t *in, const km_control_params_t *p, uint32_t ms,
                    uint8_t bit, km_prot_action_t *last)
{
    uint32_t at = 0;
    for (uint32_t t = 1; t <= ms; t++) {
        km_protect_events_t ev;
        *last = km_protect_step(s, in, p, TICK_US, &ev);
        if (at == 0u && (ev.tripped & bit) != 0u) {
            at = t;
        }
    }
    return at;
}

/* §5.2 0x3C: a sag below the low threshold trips after exactly 3 s, not
 * before; status bit 0; the default action (00) frees the output. */
static void test_s5_2_voltage_sag_trips_after_3s(void **state)
{
    (void)state;
    km_protect_t s;
    km_protect_init(&s);
    km_control_params_t p = params();
    km_protect_in_t in = nominal();
    km_prot_action_t a;
    in.voltage_mv = 5900;
    assert_int_equal(run(&s, &in, &p, 2999, KM_PROT_VOLTAGE, &a), 0);
    assert_int_equal(km_protect_state(&s, KM_PROT_VOLTAGE), KM_PROT_PENDING);
    assert_int_equal(a, KM_PROT_ACT_NONE);
    assert_int_equal(run(&s, &in, &p, 1, KM_PROT_VOLTAGE, &a), 1);
    assert_int_equal(km_protect_active(&s), KM_PROT_VOLTAGE);
    assert_int_equal(a, KM_PROT_ACT_FREE);
}

/* A sag of 2.9 s recovers without a trip, and is forgotten as fast. */
static void test_s5_2_voltage_sag_shorter_than_3s_no_trip(void **state)
{
    (void)state;
    km_protect_t s;
    km_protect_init(&s);
    km_control_params_t p = params();
    km_protect_in_t in = nominal();
    km_prot_action_t a;
    in.voltage_mv = 5000;
    assert_int_equal(run(&s, &in, &p, 2900, KM_PROT_VOLTAGE, &a), 0);
    in.voltage_mv = 7400;
    assert_int_equal(run(&s, &in, &p, 2900, KM_PROT_VOLTAGE, &a), 0);
    assert_int_equal(km_protect_state(&s, KM_PROT_VOLTAGE), KM_PROT_NORMAL);
    in.voltage_mv = 9100; /* over the high threshold next: a fresh 3 s */
    assert_int_equal(run(&s, &in, &p, 3000, KM_PROT_VOLTAGE, &a), 3000);
}

/* One noisy sample every 100 ms far over every threshold never trips. */
static void test_one_sample_spikes_never_trip(void **state)
{
    (void)state;
    km_protect_t s;
    km_protect_init(&s);
    km_control_params_t p = params();
    km_prot_action_t a;
    for (uint32_t t = 0; t < 20000; t++) {
        km_protect_in_t in = nominal();
        if (t % 100u == 0u) {
            in.voltage_mv = 20000;
            in.current_ma = 5000;
            in.temperature_c10 = 1500;
            in.drive_pwm = 1000;
        }
        km_protect_events_t ev;
        a = km_protect_step(&s, &in, &p, TICK_US, &ev);
        assert_int_equal(ev.tripped, 0);
    }
    assert_int_equal(km_protect_active(&s), 0);
    assert_int_equal(a, KM_PROT_ACT_NONE);
}

/* §5.2 0x3D: trips at 60.0 degC held 3 s; stays tripped at 56 degC;
 * released automatically only 3 s below 55.0 degC. */
static void test_s5_2_temperature_hysteresis_and_auto_release(void **state)
{
    (void)state;
    km_protect_t s;
    km_protect_init(&s);
    km_control_params_t p = params();
    km_protect_in_t in = nominal();
    km_prot_action_t a;
    in.temperature_c10 = 599;
    assert_int_equal(run(&s, &in, &p, 10000, KM_PROT_TEMPERATURE, &a), 0);
    in.temperature_c10 = 600;
    assert_int_equal(run(&s, &in, &p, 3000, KM_PROT_TEMPERATURE, &a), 3000);
    assert_int_equal(a, KM_PROT_ACT_BRAKE); /* 0x54: temperature [5:4] = 01 */
    in.temperature_c10 = 560;
    run(&s, &in, &p, 10000, KM_PROT_TEMPERATURE, &a);
    assert_int_equal(km_protect_active(&s), KM_PROT_TEMPERATURE);
    assert_false(km_protect_clear(&s, KM_PROT_TEMPERATURE)); /* still holds: refused */
    in.temperature_c10 = 549;
    run(&s, &in, &p, 2999, KM_PROT_TEMPERATURE, &a);
    assert_int_equal(km_protect_active(&s), KM_PROT_TEMPERATURE);
    km_protect_events_t ev;
    a = km_protect_step(&s, &in, &p, TICK_US, &ev);
    assert_int_equal(ev.released, KM_PROT_TEMPERATURE);
    assert_int_equal(km_protect_active(&s), 0);
    assert_int_equal(a, KM_PROT_ACT_NONE);
}

/* §5.2 0x33 = 1 for current: never released by itself; a 0x36 clear while
 * the current is still over is refused; once it is under, accepted. */
static void test_s5_2_release_by_command_only(void **state)
{
    (void)state;
    km_protect_t s;
    km_protect_init(&s);
    km_control_params_t p = params();
    p.prot_release = KM_PROT_CURRENT;
    km_protect_in_t in = nominal();
    km_prot_action_t a;
    in.current_ma = 1600;
    assert_int_equal(run(&s, &in, &p, 2000, KM_PROT_CURRENT, &a), 2000);
    assert_false(km_protect_clear(&s, KM_PROT_CURRENT));
    assert_int_equal(km_protect_active(&s), KM_PROT_CURRENT);
    in.current_ma = 0;
    run(&s, &in, &p, 60000, KM_PROT_CURRENT, &a);
    assert_int_equal(km_protect_active(&s), KM_PROT_CURRENT);
    assert_true(km_protect_clear(&s, KM_PROT_CURRENT));
    assert_int_equal(km_protect_active(&s), 0);
    assert_true(km_protect_clear(&s, KM_PROT_STALL)); /* not active: accepted, nothing */
}

/* §5.2 0x3E: the detection time is the register's, in 100 ms units:
 * pulses of 1.9 s every 10 s never trip at 2.0 s; a 2.0 s pulse does. */
static void test_s5_2_current_pulses_below_and_above_time(void **state)
{
    (void)state;
    km_protect_t s;
    km_protect_init(&s);
    km_control_params_t p = params();
    km_protect_in_t in = nominal();
    km_prot_action_t a;
    for (int k = 0; k < 5; k++) {
        in.current_ma = -1800; /* either direction */
        assert_int_equal(run(&s, &in, &p, 1900, KM_PROT_CURRENT, &a), 0);
        in.current_ma = 100;
        assert_int_equal(run(&s, &in, &p, 8100, KM_PROT_CURRENT, &a), 0);
    }
    in.current_ma = 1800;
    assert_int_equal(run(&s, &in, &p, 2000, KM_PROT_CURRENT, &a), 2000);
    assert_int_equal(a, KM_PROT_ACT_BRAKE); /* 0x54: current [3:2] = 01 */
}

/* §5.2 0x3F: stall = drive over 600 with the shaft within 1.0 deg for 2 s;
 * a shaft that keeps moving is never stalled whatever the drive. */
static void test_s5_2_stall_needs_no_motion(void **state)
{
    (void)state;
    km_protect_t s;
    km_protect_init(&s);
    km_control_params_t p = params();
    km_protect_in_t in = nominal();
    km_prot_action_t a;
    in.drive_pwm = -800;
    for (uint32_t t = 0; t < 10000; t++) {
        in.position = (int32_t)(t / 100u); /* 1 deg/s: moves out of the window every 1.1 s */
        km_protect_events_t ev;
        (void)km_protect_step(&s, &in, &p, TICK_US, &ev);
        assert_int_equal(ev.tripped, 0);
    }
    in.position = 5000;
    assert_int_equal(run(&s, &in, &p, 2000, KM_PROT_STALL, &a), 2000);
}

/* §5.2 priority: voltage (free) over stall (brake); releasing the stall
 * leaves the voltage action; releasing voltage uncovers the stall's. */
static void test_s5_2_priority_highest_decides(void **state)
{
    (void)state;
    km_protect_t s;
    km_protect_init(&s);
    km_control_params_t p = params();
    p.prot_state = 0x40 | 0x00; /* stall 01 brake, voltage 00 free */
    p.prot_release = KM_PROT_ALL;
    km_protect_in_t in = nominal();
    km_prot_action_t a;
    in.drive_pwm = 900;
    in.voltage_mv = 5000;
    run(&s, &in, &p, 3000, KM_PROT_ALL, &a);
    assert_int_equal(km_protect_active(&s), KM_PROT_VOLTAGE | KM_PROT_STALL);
    assert_int_equal(a, KM_PROT_ACT_FREE);
    in.drive_pwm = 0;
    in.voltage_mv = 7400;
    run(&s, &in, &p, 10, KM_PROT_ALL, &a);
    assert_true(km_protect_clear(&s, KM_PROT_STALL));
    run(&s, &in, &p, 1, KM_PROT_ALL, &a);
    assert_int_equal(a, KM_PROT_ACT_FREE); /* voltage still active */
    assert_true(km_protect_clear(&s, KM_PROT_VOLTAGE));
    run(&s, &in, &p, 1, KM_PROT_ALL, &a);
    assert_int_equal(a, KM_PROT_ACT_NONE);
}

/* §5.2 0x34 1x (hold): only current and stall, only in servo mode; in
 * motor mode (or for voltage/temperature) it acts as brake. */
static void test_s5_2_hold_only_where_allowed(void **state)
{
    (void)state;
    km_control_params_t p = params();
    p.prot_state = 0xFF; /* every field 11 */
    const struct {
        uint8_t bit;
        bool servo_mode;
        km_prot_action_t want;
    } rows[] = {
        {KM_PROT_STALL, true, KM_PROT_ACT_HOLD},    {KM_PROT_STALL, false, KM_PROT_ACT_BRAKE},
        {KM_PROT_CURRENT, true, KM_PROT_ACT_HOLD},  {KM_PROT_CURRENT, false, KM_PROT_ACT_BRAKE},
        {KM_PROT_VOLTAGE, true, KM_PROT_ACT_BRAKE}, {KM_PROT_TEMPERATURE, true, KM_PROT_ACT_BRAKE},
    };
    for (size_t i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        km_protect_t s;
        km_protect_init(&s);
        km_protect_in_t in = nominal();
        in.servo_mode = rows[i].servo_mode;
        if (rows[i].bit == KM_PROT_STALL) {
            in.drive_pwm = 900;
        } else if (rows[i].bit == KM_PROT_CURRENT) {
            in.current_ma = 3000;
        } else if (rows[i].bit == KM_PROT_VOLTAGE) {
            in.voltage_mv = 12000;
        } else {
            in.temperature_c10 = 700;
        }
        km_prot_action_t a;
        assert_int_not_equal(run(&s, &in, &p, 3000, rows[i].bit, &a), 0);
        assert_int_equal(a, rows[i].want);
    }
}

/* §5.2 0x32: a disabled protection never trips, and disabling an active
 * one releases it at once. */
static void test_s5_2_disabled_never_trips(void **state)
{
    (void)state;
    km_protect_t s;
    km_protect_init(&s);
    km_control_params_t p = params();
    p.prot_enable = KM_PROT_ALL & (uint8_t)~KM_PROT_TEMPERATURE;
    km_protect_in_t in = nominal();
    km_prot_action_t a;
    in.temperature_c10 = 1200;
    assert_int_equal(run(&s, &in, &p, 60000, KM_PROT_TEMPERATURE, &a), 0);
    p.prot_enable = KM_PROT_ALL;
    assert_int_equal(run(&s, &in, &p, 3000, KM_PROT_TEMPERATURE, &a), 3000);
    p.prot_enable = 0;
    km_protect_events_t ev;
    a = km_protect_step(&s, &in, &p, TICK_US, &ev);
    assert_int_equal(ev.released, KM_PROT_TEMPERATURE);
    assert_int_equal(a, KM_PROT_ACT_NONE);
}

/* Chatter at a threshold: 60 % of the time over trips (later than T), 40 %
 * never does (the up/down timer's bound). */
static void test_chatter_at_threshold(void **state)
{
    (void)state;
    const struct {
        uint32_t over_ms;
        uint32_t period_ms;
        bool trips;
    } rows[] = {{6, 10, true}, {4, 10, false}, {600, 1000, true}, {400, 1000, false}};
    for (size_t i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        km_protect_t s;
        km_protect_init(&s);
        km_control_params_t p = params();
        uint32_t at = 0;
        for (uint32_t t = 0; t < 60000 && at == 0u; t++) {
            km_protect_in_t in = nominal();
            in.voltage_mv = (t % rows[i].period_ms) < rows[i].over_ms ? 9200 : 8900;
            km_protect_events_t ev;
            (void)km_protect_step(&s, &in, &p, TICK_US, &ev);
            if (ev.tripped != 0u) {
                at = t + 1u;
            }
        }
        assert_int_equal(at != 0u, rows[i].trips);
        if (rows[i].trips) {
            assert_true(at > 3000u);
        }
    }
}

/* 0x3E/0x3F detection time 0: the shortest, one tick. */
static void test_detection_time_zero_is_one_tick(void **state)
{
    (void)state;
    km_protect_t s;
    km_protect_init(&s);
    km_control_params_t p = params();
    p.current_time_100ms = 0;
    km_protect_in_t in = nominal();
    km_prot_action_t a;
    in.current_ma = 1501;
    assert_int_equal(run(&s, &in, &p, 1, KM_PROT_CURRENT, &a), 1);
    in.current_ma = 1500; /* not over: "above" the threshold only */
    km_protect_events_t ev;
    (void)km_protect_step(&s, &in, &p, TICK_US, &ev);
    assert_int_equal(ev.released, KM_PROT_CURRENT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s5_2_voltage_sag_trips_after_3s),
        cmocka_unit_test(test_s5_2_voltage_sag_shorter_than_3s_no_trip),
        cmocka_unit_test(test_one_sample_spikes_never_trip),
        cmocka_unit_test(test_s5_2_temperature_hysteresis_and_auto_release),
        cmocka_unit_test(test_s5_2_release_by_command_only),
        cmocka_unit_test(test_s5_2_current_pulses_below_and_above_time),
        cmocka_unit_test(test_s5_2_stall_needs_no_motion),
        cmocka_unit_test(test_s5_2_priority_highest_decides),
        cmocka_unit_test(test_s5_2_hold_only_where_allowed),
        cmocka_unit_test(test_s5_2_disabled_never_trips),
        cmocka_unit_test(test_chatter_at_threshold),
        cmocka_unit_test(test_detection_time_zero_is_one_tick),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
