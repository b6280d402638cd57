/* SPDX-License-Identifier: Apache-2.0 */
/* A request for less motion is always accepted (issue 18 item 4;
 * docs/protocol-decisions.md "Protections"): through the whole control tick
 * on the plant (km_control_step via the plant rig), while a protection acts
 * (docs/protocol.md §5.2 0x34, §5.4 0x64 = 5) and while a hardware fault is
 * latched (§5.2 0x35, §4 bit 4). Less motion: 0x64 = 0/1, 0x6E = 0,
 * 0x6F = 0, 0x70 with its stop bit (bit 7) or with nothing to run. Each is
 * accepted (no status bit 6), the output never drives because of it, and
 * nothing starts again when the protection is released; every request for
 * more motion is still refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "km_plant_rig.h"

/* One request for less motion, by name. */
typedef struct {
    const char *name;
    km_request_t req;
} less_t;

/* The requests as the dispatcher's hooks decode the frames named. */
#define REQ_TS(v)                                    \
    {                                                \
        .kind = KM_REQ_TORQUE, .u = {.torque = (v) } \
    }
#define REQ_RUN(m_, rev_, v_, until_, amount_, after_) \
    {                                                  \
        .kind = KM_REQ_MOTOR, .u = {                   \
            .run = {.mode = (m_),                      \
                    .reverse = (rev_),                 \
                    .value = (v_),                     \
                    .until = (until_),                 \
                    .amount = (amount_),               \
                    .after = (after_)}                 \
        }                                              \
    }
/* 0x6E (PWM) or 0x6F (speed) = v: run on, the idle output at 0. */
#define REQ_MOTOR(m, v) \
    REQ_RUN((m), (v) < 0, (uint16_t)((v) < 0 ? -(v) : (v)), KM_UNTIL_NONE, 0, KM_AFTER_IDLE)
#define REQ_MOVE(k_, rel_, t_, ts_)                                                                          \
    {                                                                                                        \
        .kind = KM_REQ_MOVE, .u =                                                                            \
        {.move = {.kind = (k_), .relative = (rel_), .target = (t_), .time_or_speed = (ts_), .pwm_cap = 1000} \
        }                                                                                                    \
    }

static const less_t k_less[] = {
    {"0x64 = 0", REQ_TS(0)},
    {"0x64 = 1", REQ_TS(1)},
    {"0x6E = 0", REQ_MOTOR(KM_RUN_PWM, 0)},
    {"0x6F = 0", REQ_MOTOR(KM_RUN_SPEED, 0)},
    {"0x70 stop, free after", REQ_RUN(KM_RUN_STOP, false, 0, KM_UNTIL_NONE, 0, KM_AFTER_FREE)},
    {"0x70 stop, brake after", REQ_RUN(KM_RUN_STOP, false, 0, KM_UNTIL_NONE, 0, KM_AFTER_BRAKE)},
    {"0x70 stop with a run in its fields",
     REQ_RUN(KM_RUN_STOP, true, 800, KM_UNTIL_TIME, 50, KM_AFTER_BRAKE)},
    {"0x70 run on at PWM 0", REQ_RUN(KM_RUN_PWM, false, 0, KM_UNTIL_NONE, 0, KM_AFTER_FREE)},
    {"0x70 run for 0 s at PWM 500", REQ_RUN(KM_RUN_PWM, false, 500, KM_UNTIL_TIME, 0, KM_AFTER_FREE)},
};
#define N_LESS (sizeof k_less / sizeof k_less[0])

/* Requests for more motion: still refused. */
static void more_motion_refused(kr_rig_t *r)
{
    static const km_request_t more[] = {
        REQ_TS(2),
        REQ_TS(3),
        REQ_MOTOR(KM_RUN_PWM, 500),
        REQ_MOTOR(KM_RUN_PWM, -1),
        REQ_MOTOR(KM_RUN_SPEED, 30),
        REQ_RUN(KM_RUN_PWM, false, 500, KM_UNTIL_TIME, 5, KM_AFTER_FREE),  /* 0x70 0x10, 0.5 s at 500 */
        REQ_RUN(KM_RUN_SPEED, false, 90, KM_UNTIL_NONE, 0, KM_AFTER_FREE), /* 0x70 0x04, 90 deg/s */
        REQ_MOVE(KM_MOVE_TIME, false, 300, 500),
        REQ_MOVE(KM_MOVE_SPEED, false, -300, 0),
        REQ_MOVE(KM_MOVE_STREAM, false, 100, 0),
        REQ_MOVE(KM_MOVE_TIME, true, 100, 500), /* 0x67 0x10 */
    };
    for (size_t i = 0; i < sizeof more / sizeof more[0]; i++) {
        assert_false(kr_request(r, &more[i]));
    }
}

/* The protection settings of the product defaults (0x32 0x0F, 0x33 0,
 * 0x34 0x54: voltage frees, the others brake; 0x3C 9/6 V). */
static void protections_on(kr_rig_t *r)
{
    r->params.prot_enable = 0x0F;
    r->params.prot_release = 0x00;
    r->params.prot_state = 0x54;
    r->params.voltage_high_v = 9;
    r->params.voltage_low_v = 6;
    r->params.temp_trip_c = 60;
    r->params.temp_hysteresis_c = 5;
    r->params.current_trip_ma = 1500;
    r->params.current_time_100ms = 20;
    r->params.stall_pwm = 600;
    r->params.stall_time_100ms = 20;
}

/* Runs `ms` ticks; fails if the bridge is driven on any of them. */
static void run_never_driven(kr_rig_t *r, uint32_t ms)
{
    for (uint32_t i = 0; i < ms; i++) {
        kr_tick(r);
        assert_int_not_equal(r->bridge.mode, KM_BRIDGE_PWM);
    }
}

/* A servo whose motor runs at 0x6E = 400 when the supply sags to 5.0 V:
 * after 3 s the voltage protection frees the output (0x34 bits 1:0 = 00). */
static void boot_motor_then_sag(kr_rig_t *r)
{
    kr_init(r);
    protections_on(r);
    kr_run(r, 50);
    const km_request_t run = REQ_MOTOR(KM_RUN_PWM, 400);
    assert_true(kr_request(r, &run));
    kr_run(r, 200);
    assert_true(r->live.running);
    km_plant_set_supply_mv(&r->plant, 5000);
    kr_run(r, 3001);
    assert_true(r->live.protecting);
    assert_int_equal(r->live.protections, KM_PROT_VOLTAGE);
    assert_int_equal(r->live.torque_switch, 5);
    assert_int_equal(r->bridge.mode, KM_BRIDGE_FREE);
}

/* §5.2 0x34, §5.4 0x64 = 5: while the voltage protection acts, every request
 * for less motion is accepted (no bit 6), the output stays as the
 * protection set it, and after the automatic release (3 s after the supply
 * is back) the motor does not start again. */
static void test_s5_2_less_motion_accepted_while_protecting(void **state)
{
    (void)state;
    for (size_t k = 0; k < N_LESS; k++) {
        kr_rig_t r;
        boot_motor_then_sag(&r);
        more_motion_refused(&r);
        assert_true(kr_request(&r, &k_less[k].req));
        run_never_driven(&r, 500);
        assert_true(r.live.protecting);
        assert_int_equal(r.bridge.mode, KM_BRIDGE_FREE); /* the protection's action has the last word */
        km_plant_set_supply_mv(&r.plant, 7400);
        run_never_driven(&r, 3100);
        assert_false(r.live.protecting);
        assert_false(r.live.running);
        run_never_driven(&r, 1000);
        printf("  protecting: %-36s accepted, never driven, 0x64 -> %u after the release\n", k_less[k].name,
               (unsigned)r.live.torque_switch);
    }
}

/* §5.2 0x34 hold (1x, current protection, servo mode): a request for less
 * motion ends the hold: 0x64 = 0 lets go (free), 0x6E = 0 leaves the idle
 * output (0x11 bit 1: brake); the bridge is not driven again. */
static void test_s5_2_less_motion_ends_a_protection_hold(void **state)
{
    (void)state;
    const km_request_t stops[] = {REQ_TS(0), REQ_MOTOR(KM_RUN_PWM, 0)};
    const km_bridge_mode_t after[] = {KM_BRIDGE_FREE, KM_BRIDGE_BRAKE};
    for (size_t k = 0; k < 2; k++) {
        kr_rig_t r;
        kr_init(&r);
        protections_on(&r);
        r.params.prot_state = 0x58; /* current: 10 = hold */
        r.params.current_trip_ma = 300;
        r.params.current_time_100ms = 2; /* 200 ms */
        kr_run(&r, 50);
        assert_true(kr_torque(&r, 2));
        kr_run(&r, 100);
        r.in.ext_torque_unm = -1000000; /* 1 N.m against the hold: ~1.3 A */
        uint32_t ms = 0;
        while (!r.live.protecting && ms < 2000u) {
            kr_tick(&r);
            ms++;
        }
        assert_true(r.live.protecting);
        assert_int_equal(r.live.protections, KM_PROT_CURRENT);
        kr_run(&r, 50);
        assert_int_equal(r.bridge.mode, KM_BRIDGE_PWM); /* holding where it tripped */
        assert_true(kr_request(&r, &stops[k]));
        run_never_driven(&r, 2000);
        assert_int_equal(r.bridge.mode, after[k]);
    }
}

/* §5.2 0x35, §4 bit 4: with a hardware fault latched (an NTC open at boot),
 * every request for less motion is accepted and none drives the output;
 * every request for more motion is refused. 0x70 stop with brake (bit 1)
 * brakes, as 0x64 = 1 does. */
static void test_s5_2_less_motion_accepted_with_hardware_fault(void **state)
{
    (void)state;
    for (size_t k = 0; k < N_LESS; k++) {
        kr_rig_t r;
        kr_init(&r);
        km_plant_set_faults(&r.plant, KM_PLANT_FAULT_TEMP_OPEN);
        km_control_init(&r.ctl, &r.params); /* booted with it */
        kr_run(&r, 50);
        assert_int_equal(r.live.hw_faults, KM_HW_TEMPERATURE);
        more_motion_refused(&r);
        assert_true(kr_request(&r, &k_less[k].req));
        run_never_driven(&r, 500);
        more_motion_refused(&r);
        assert_int_equal(r.live.hw_faults, KM_HW_TEMPERATURE);
        printf("  hardware fault: %-36s accepted, never driven, output %s\n", k_less[k].name,
               r.bridge.mode == KM_BRIDGE_BRAKE ? "brake" : "free");
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s5_2_less_motion_accepted_while_protecting),
        cmocka_unit_test(test_s5_2_less_motion_ends_a_protection_hold),
        cmocka_unit_test(test_s5_2_less_motion_accepted_with_hardware_fault),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
