/* SPDX-License-Identifier: Apache-2.0 */
/* control/km_control.c, the tick without the plant (the plant-backed
 * motion tests are tests/unit/control/test_control_servo.c):
 * docs/protocol.md §5.1 zero offsets 0x16 + 0x17 and direction (0x11 bit 2),
 * §5.1 0x11 bits 0/1 power-on and idle output, §5.4 0x64 torque switch to
 * bridge mode, §5.3 live registers (speed over a 20 ms window, current,
 * voltage, temperature, 0x35 hardware faults). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_control.h"

static km_control_t c;

/* Params as the dispatcher decodes them from 0x16, 0x17, 0x11 and 0x64
 * (the rest at the values a fresh servo has). */
static km_control_params_t cfg_of(int16_t zo1, int16_t zo2, uint8_t config, uint8_t torque_switch)
{
    km_control_params_t cfg;
    memset(&cfg, 0, sizeof cfg);
    const km_control_gains_t g = KM_CONTROL_GAINS_DEFAULT;
    cfg.zero_offset1 = zo1;
    cfg.zero_offset2 = zo2;
    cfg.reverse = (config & 0x04) != 0;
    cfg.idle_brake = (config & 0x02) != 0;
    cfg.power_on_brake = (config & 0x01) != 0;
    cfg.torque_switch = torque_switch;
    cfg.max_torque = 1000;
    cfg.torque_limit = 1000;
    cfg.speed_limit_dps = 360;
    cfg.max_speed_dps = 360;
    cfg.travel_min = -32000;
    cfg.travel_max = 32000;
    cfg.pos_read_min = -32000;
    cfg.pos_read_max = 32000;
    cfg.gains = g;
    return cfg;
}

static km_sensors_t sensors_at(int32_t position)
{
    km_sensors_t in;
    memset(&in, 0, sizeof in);
    in.position = position;
    return in;
}

/* One tick; returns the live state and checks the bridge output equals the
 * control's own bridge command. */
static km_live_t step(const km_sensors_t *in, const km_control_params_t *cfg, uint32_t dt_us)
{
    km_live_t live;
    memset(&live, 0x5A, sizeof live); /* every field must be written */
    km_bridge_t bridge = {(km_bridge_mode_t)99, 1234};
    km_control_step(&c, in, cfg, dt_us, &live, &bridge);
    assert_int_equal(bridge.mode, c.bridge.mode);
    assert_int_equal(bridge.pwm, c.bridge.pwm);
    return live;
}

static void torque_switch(uint8_t v, const km_control_params_t *cfg)
{
    km_request_t req;
    memset(&req, 0, sizeof req);
    req.kind = KM_REQ_TORQUE;
    req.u.torque = v;
    assert_true(km_control_request(&c, &req, cfg));
}

/* §5.1: reported position = sensor + level-1 zero offset (0x16) + level-2
 * zero offset (0x17), in 0.1 deg. */
static void test_s5_1_position_is_sensor_plus_both_zero_offsets(void **state)
{
    (void)state;
    static const struct {
        int32_t sensor;
        int16_t zo1, zo2;
        int32_t want;
    } t[] = {
        {100, 37, -20, 117},
        {0, 0, 0, 0},
        {-900, -12, 0, -912},
        {1350, 0, 300, 1650},
        {-32768, -32768, -32768, -98304}, /* no 16-bit wrap */
        {123456, 5, 5, 123466},
    };
    for (unsigned i = 0; i < sizeof t / sizeof t[0]; i++) {
        const km_control_params_t cfg = cfg_of(t[i].zo1, t[i].zo2, 0x02, 3);
        km_control_init(&c, &cfg);
        const km_sensors_t in = sensors_at(t[i].sensor);
        const km_live_t live = step(&in, &cfg, 1000);
        assert_int_equal(live.position, t[i].want);
    }
}

/* §5.1 0x16, 0x17 and 0x11 bit 2 changed while holding: every position
 * control keeps (the reading, the speed estimates' samples, the hold
 * filter, the held target) is the same shaft angle in the new frame,
 * exactly km_axis_map's; the speeds and the integral change sign with the
 * direction (docs/control-design.md). */
static void test_s5_1_frame_change_maps_the_state_exactly(void **state)
{
    (void)state;
    const km_control_params_t was_cfg = cfg_of(123, -45, 0x02, KM_TORQUE_ON);
    const km_control_params_t now_cfg = cfg_of(-700, 31, 0x02 | 0x04, KM_TORQUE_ON);
    km_control_init(&c, &was_cfg);
    torque_switch(KM_TORQUE_ON, &was_cfg);
    for (int32_t k = 0; k < 40; k++) {
        km_sensors_t in = sensors_at(1000 + 7 * k);
        in.voltage_mv = 7400; /* sound sensors: no hardware fault lets go */
        in.temperature_c10 = 250;
        (void)step(&in, &was_cfg, 1000);
    }
    const km_control_t before = c;
    const km_axis_t was = km_axis_of(&was_cfg), now = km_axis_of(&now_cfg);
    assert_int_equal(before.servo.ts, KM_TORQUE_ON);
    assert_true(before.hold.on);
    assert_int_not_equal(before.fast.ddps, 0);
    km_request_t req;
    memset(&req, 0, sizeof req);
    req.kind = KM_REQ_ZERO_POSITION; /* follows the frame, moves nothing */
    assert_true(km_control_request(&c, &req, &now_cfg));
    for (uint32_t k = 0; k < KM_SPEED_FAST_N; k++) {
        assert_int_equal(c.fast.pos[k], km_axis_map(&was, &now, before.fast.pos[k]));
    }
    assert_int_equal(c.speed.last_position, km_axis_map(&was, &now, before.speed.last_position));
    assert_int_equal(c.hold.out, km_axis_map(&was, &now, before.hold.out));
    assert_int_equal(c.position, km_axis_map(&was, &now, before.position));
    assert_int_equal(c.servo.target, km_axis_map(&was, &now, before.servo.target));
    assert_int_equal(c.fast.ddps, -before.fast.ddps);
    assert_int_equal(c.speed.dps, -before.speed.dps);
    assert_int_equal(c.hold.frac, -before.hold.frac);
    assert_int_equal(c.loop.i_acc, -before.loop.i_acc);
}

/* §5.1 0x11 bit 2 direction: set, the reported position (offsets applied)
 * changes sign; clear, it does not. */
static void test_s5_1_direction_bit_flips_position(void **state)
{
    (void)state;
    const km_control_params_t fwd = cfg_of(37, -20, 0x02, 3);
    const km_control_params_t rev = cfg_of(37, -20, 0x02 | 0x04, 3);
    km_control_init(&c, &fwd);
    const km_sensors_t in = sensors_at(100);
    assert_int_equal(step(&in, &fwd, 1000).position, 117);
    km_control_init(&c, &rev);
    assert_int_equal(step(&in, &rev, 1000).position, -117);
    /* other bits (response level, output bits) do not flip it */
    const km_control_params_t other = cfg_of(37, -20, 0x0B, 3);
    km_control_init(&c, &other);
    assert_int_equal(step(&in, &other, 1000).position, 117);
}

/* §5.1 0x11 bit 0 power-on output: 0 free, 1 brake damping, from init on. */
static void test_s5_1_power_on_output_bit0(void **state)
{
    (void)state;
    for (uint8_t config = 0; config < 16; config++) {
        const km_control_params_t cfg = cfg_of(0, 0, config, 3);
        memset(&c, 0xA5, sizeof c);
        km_control_init(&c, &cfg);
        const km_bridge_mode_t want = (config & 0x01) ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE;
        assert_int_equal(c.bridge.mode, want);
        assert_int_equal(c.bridge.pwm, 0);
        assert_int_equal(c.requests, 0);
        const km_sensors_t in = sensors_at(0);
        (void)step(&in, &cfg, 1000); /* the first tick outputs it */
        assert_int_equal(c.bridge.mode, want);
    }
}

/* §5.4 0x64 as the bridge sees it after the next tick: 0 free, 1 brake
 * damping whatever 0x11 says; 2 on (the position loop drives: PWM, 0 at
 * the held position); 3 armed = off, the idle output of 0x11 bit 1. */
static void test_s5_4_torque_switch_bridge_mode(void **state)
{
    (void)state;
    for (uint8_t config = 0; config < 16; config++) {
        const km_control_params_t cfg = cfg_of(0, 0, config, 3);
        const km_bridge_mode_t idle = (config & 0x02) ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE;
        static const uint8_t order[] = {0, 1, 2, 0, 3, 1, 2, 3};
        km_control_init(&c, &cfg);
        for (unsigned i = 0; i < sizeof order; i++) {
            torque_switch(order[i], &cfg);
            km_bridge_mode_t want = idle;
            if (order[i] == 0)
                want = KM_BRIDGE_FREE;
            if (order[i] == 1)
                want = KM_BRIDGE_BRAKE;
            if (order[i] == 2)
                want = KM_BRIDGE_PWM;
            const km_sensors_t in = sensors_at(0);
            const km_live_t live = step(&in, &cfg, 1000);
            if (c.bridge.mode != want) {
                fail_msg("0x11 = 0x%02X, 0x64 = %u: bridge %d, want %d", config, order[i], c.bridge.mode,
                         want);
            }
            assert_int_equal(live.pwm, 0); /* holding where it is: no error, no PWM */
            assert_false(live.running);
        }
        assert_int_equal(c.requests, sizeof order);
        assert_int_equal(c.last_request.kind, KM_REQ_TORQUE);
        assert_int_equal(c.last_request.u.torque, 3);
    }
}

/* Rotation requests with the torque off (0x64 = 0, 1) are refused and
 * leave the bridge as it is; motor-mode requests are accepted and counted
 * and run whatever 0x64 is (§5.4: motor mode does not need the servo-mode
 * torque switch; test_control_motor.c has the rest). */
static void test_motion_refused_torque_off_motor_counted(void **state)
{
    (void)state;
    const km_control_params_t cfg = cfg_of(0, 0, 0x02, 3);
    km_control_init(&c, &cfg);
    torque_switch(1, &cfg);
    km_request_t req;
    memset(&req, 0, sizeof req);
    req.kind = KM_REQ_MOVE;
    req.u.move.kind = KM_MOVE_TIME;
    req.u.move.target = 900;
    req.u.move.time_or_speed = 1000;
    req.u.move.pwm_cap = 1000;
    assert_false(km_control_request(&c, &req, &cfg));
    assert_int_equal(c.requests, 2);
    assert_int_equal(c.last_request.kind, KM_REQ_MOVE);
    assert_int_equal(c.last_request.u.move.target, 900);
    assert_int_equal(c.last_request.u.move.time_or_speed, 1000);
    const km_sensors_t in = sensors_at(0);
    assert_false(step(&in, &cfg, 1000).running);
    assert_int_equal(c.bridge.mode, KM_BRIDGE_BRAKE);
    memset(&req, 0, sizeof req);
    req.kind = KM_REQ_MOTOR;
    req.u.run.mode = KM_RUN_PWM;
    req.u.run.reverse = true;
    req.u.run.value = 500;
    req.u.run.after = KM_AFTER_IDLE;
    assert_true(km_control_request(&c, &req, &cfg));
    assert_int_equal(c.requests, 3);
    (void)step(&in, &cfg, 1000);
    assert_int_equal(c.bridge.mode, KM_BRIDGE_PWM);
    assert_int_equal(c.bridge.pwm, -500);
}

/* Runs `ticks` ticks of `dt_us`, the sensor moving `per_tick` 0.1 deg each;
 * returns the last live state. */
static km_live_t ramp(int32_t *pos, int32_t per_tick, unsigned ticks, uint32_t dt_us,
                      const km_control_params_t *cfg)
{
    km_live_t live = {0};
    for (unsigned i = 0; i < ticks; i++) {
        *pos += per_tick;
        const km_sensors_t in = sensors_at(*pos);
        live = step(&in, cfg, dt_us);
    }
    return live;
}

/* §5.3 0x47 speed: position change over a 20 ms window, deg/s. A ramp of
 * 0.1 deg per 1 ms is 100 deg/s; the value holds until the next window
 * completes; no speed before the first window. */
static void test_s5_3_speed_over_20ms_window(void **state)
{
    (void)state;
    const km_control_params_t cfg = cfg_of(0, 0, 0x02, 3);
    km_control_init(&c, &cfg);
    int32_t pos = 500;
    const km_sensors_t first = sensors_at(pos);
    assert_int_equal(step(&first, &cfg, 1000).speed, 0);       /* the first sample only sets the origin */
    assert_int_equal(ramp(&pos, 1, 19, 1000, &cfg).speed, 0);  /* 19 ms: window not full */
    assert_int_equal(ramp(&pos, 1, 1, 1000, &cfg).speed, 100); /* 2 deg in 20 ms */
    /* the next window: -0.5 deg per ms = -500 deg/s; held until it completes */
    assert_int_equal(ramp(&pos, -5, 19, 1000, &cfg).speed, 100);
    assert_int_equal(ramp(&pos, -5, 1, 1000, &cfg).speed, -500);
    /* standing still */
    assert_int_equal(ramp(&pos, 0, 20, 1000, &cfg).speed, 0);
    /* 5 ms ticks: four make a window; 3 x 0.1 deg per 5 ms = 60 deg/s */
    assert_int_equal(ramp(&pos, 3, 3, 5000, &cfg).speed, 0);
    assert_int_equal(ramp(&pos, 3, 1, 5000, &cfg).speed, 60);
    /* a window that overshoots 20 ms divides by the time it really took:
     * 7 ms ticks, 3 ticks = 21 ms, 21 x 0.1 deg -> 100 deg/s */
    assert_int_equal(ramp(&pos, 7, 2, 7000, &cfg).speed, 60);
    assert_int_equal(ramp(&pos, 7, 1, 7000, &cfg).speed, 100);
}

/* Speed follows the reported position: with the direction bit set a
 * rising sensor is a negative speed; zero offsets do not add speed. */
static void test_s5_3_speed_follows_direction(void **state)
{
    (void)state;
    const km_control_params_t rev = cfg_of(37, 100, 0x06, 3);
    km_control_init(&c, &rev);
    int32_t pos = 0;
    const km_sensors_t first = sensors_at(pos);
    (void)step(&first, &rev, 1000);
    const km_live_t live = ramp(&pos, 2, 20, 1000, &rev);
    assert_int_equal(live.speed, -200);
    assert_int_equal(live.position, -(40 + 37 + 100));
}

/* §5.3 live fields copied from the sensors: current mA, voltage mV,
 * temperature 0.1 degC -> degC (integer division), 0x35 fault bits; with
 * the torque armed (off) the rest of km_live_t (running, protections,
 * deviation, rotation time, PWM) is 0. */
static void test_s5_3_live_fields_from_sensors(void **state)
{
    (void)state;
    const km_control_params_t cfg = cfg_of(0, 0, 0x02, 3);
    km_control_init(&c, &cfg);
    static const struct {
        int32_t cur, mv, c10;
        uint8_t faults;
        int32_t want_c;
    } t[] = {
        {1500, 12100, 415, 0x00, 41},   {-800, 7400, 419, 0x20, 41}, {0, 0, 0, 0xFF, 0},
        {3000, 25000, 1000, 0x81, 100}, {12, 5000, -15, 0x04, -1},
    };
    uint8_t latched = 0;
    for (unsigned i = 0; i < sizeof t / sizeof t[0]; i++) {
        km_sensors_t in = sensors_at(10);
        in.current_ma = t[i].cur;
        in.voltage_mv = t[i].mv;
        in.temperature_c10 = t[i].c10;
        in.faults = t[i].faults;
        const km_live_t live = step(&in, &cfg, 1000);
        assert_int_equal(live.current, t[i].cur);
        assert_int_equal(live.voltage, t[i].mv);
        assert_int_equal(live.temperature, t[i].want_c);
        /* §5.2 0x35: the hal's fault bits are latched (until restart);
         * five ticks are too few for the self-test's own verdicts */
        latched |= t[i].faults;
        assert_int_equal(live.hw_faults, latched);
        assert_int_equal(live.position, 10);
        assert_int_equal(live.pwm, 0);
        assert_int_equal(live.deviation, 0);
        assert_int_equal(live.rotation_ms, 0);
        assert_false(live.running);
        assert_int_equal(live.protections, 0);
    }
}

/* Runs ticks of 1 ms until `done` holds for the live state or `max` ticks
 * passed; returns the ticks run. */
static unsigned run_until(const km_sensors_t *in, const km_control_params_t *cfg, km_live_t *live,
                          bool (*done)(const km_live_t *), unsigned max)
{
    for (unsigned t = 1; t <= max; t++) {
        *live = step(in, cfg, 1000);
        if (done(live)) {
            return t;
        }
    }
    return max + 1u;
}

static bool has_event(const km_live_t *l)
{
    return (l->events.tripped | l->events.released | l->events.cleared | l->events.hw_found) != 0u;
}

/* The fault log's one source (issue 19): control reports each protection
 * event once, at the tick it happens: a trip (§5.2 0x3C, 3 s detection),
 * the release a clear request made (0x36 write: "cleared", at the next
 * tick, never "released"), an automatic release ("released"), a hardware
 * fault found (0x35). While a protection acts and at the tick it ends, and
 * when a fault stops the output, it says it set the torque switch itself
 * (torque_forced: 5 while acting, what it returns to after), and only then. */
static void test_protection_events_reported_once(void **state)
{
    (void)state;
    km_control_params_t cfg = cfg_of(0, 0, 0x02, 3);
    cfg.prot_enable = KM_PROT_VOLTAGE;
    cfg.prot_release = KM_PROT_VOLTAGE; /* only by command */
    cfg.voltage_high_v = 14;
    cfg.voltage_low_v = 6;
    km_control_init(&c, &cfg);
    km_sensors_t in = sensors_at(0);
    in.voltage_mv = 7400;
    in.temperature_c10 = 250;
    km_live_t live;
    assert_int_equal(run_until(&in, &cfg, &live, has_event, 100), 101u); /* a healthy boot: nothing */
    assert_false(live.torque_forced);
    in.voltage_mv = 5000;
    const unsigned t = run_until(&in, &cfg, &live, has_event, 4000);
    assert_true(t >= 3000u && t <= 3001u);
    assert_int_equal(live.events.tripped, KM_PROT_VOLTAGE);
    assert_int_equal(live.events.released | live.events.cleared | live.events.hw_found, 0);
    assert_true(live.protecting && live.torque_forced);
    assert_int_equal(live.torque_switch, KM_TORQUE_PROTECTED);
    in.voltage_mv = 7400;
    assert_int_equal(run_until(&in, &cfg, &live, has_event, 5000),
                     5001u); /* held: released only by command */
    assert_true(live.protecting && live.torque_forced);
    km_request_t clear;
    memset(&clear, 0, sizeof clear);
    clear.kind = KM_REQ_PROTECTION_CLEAR;
    clear.u.clear = KM_PROT_VOLTAGE;
    assert_true(km_control_request(&c, &clear, &cfg));
    live = step(&in, &cfg, 1000);
    assert_int_equal(live.events.cleared, KM_PROT_VOLTAGE);
    assert_int_equal(live.events.tripped | live.events.released | live.events.hw_found, 0);
    assert_false(live.protecting);
    assert_true(live.torque_forced); /* the release tick: back to armed */
    assert_int_equal(live.torque_switch, KM_TORQUE_ARMED);
    live = step(&in, &cfg, 1000);
    assert_false(has_event(&live));
    assert_false(live.torque_forced);
    /* automatic release: absent for 3 s */
    cfg.prot_release = 0;
    in.voltage_mv = 5000;
    assert_true(run_until(&in, &cfg, &live, has_event, 4000) <= 4000u);
    assert_int_equal(live.events.tripped, KM_PROT_VOLTAGE);
    in.voltage_mv = 7400;
    assert_true(run_until(&in, &cfg, &live, has_event, 4000) <= 4000u);
    assert_int_equal(live.events.released, KM_PROT_VOLTAGE);
    assert_int_equal(live.events.tripped | live.events.cleared | live.events.hw_found, 0);
    assert_true(live.torque_forced);
    /* a hardware fault the sensors flag: found once, the output stopped */
    assert_true(run_until(&in, &cfg, &live, has_event, 10) == 11u);
    assert_false(live.torque_forced);
    in.faults = KM_HW_POSITION;
    live = step(&in, &cfg, 1000);
    assert_int_equal(live.events.hw_found, KM_HW_POSITION);
    assert_true(live.torque_forced);
    assert_int_equal(live.torque_switch, KM_TORQUE_FREE);
    live = step(&in, &cfg, 1000);
    assert_false(has_event(&live));
    assert_false(live.torque_forced);
    assert_int_equal(live.hw_faults, KM_HW_POSITION);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s5_1_position_is_sensor_plus_both_zero_offsets),
        cmocka_unit_test(test_s5_1_frame_change_maps_the_state_exactly),
        cmocka_unit_test(test_s5_1_direction_bit_flips_position),
        cmocka_unit_test(test_s5_1_power_on_output_bit0),
        cmocka_unit_test(test_s5_4_torque_switch_bridge_mode),
        cmocka_unit_test(test_motion_refused_torque_off_motor_counted),
        cmocka_unit_test(test_s5_3_speed_over_20ms_window),
        cmocka_unit_test(test_s5_3_speed_follows_direction),
        cmocka_unit_test(test_s5_3_live_fields_from_sensors),
        cmocka_unit_test(test_protection_events_reported_once),
    };
    return cmocka_run_group_tests_name("control", tests, NULL, NULL);
}
