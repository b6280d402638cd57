/* SPDX-License-Identifier: Apache-2.0 */
/* Protections and the fault log through the whole firmware, bytes on the
 * simulated wire in virtual time (docs/protocol.md §5.2 0x33/0x35/0x36, §4 bits
 * 0-4 and 6, §5.4 0x64 = 5; the fault log of docs/protocol-decisions.md,
 * read with 0x7F): the dispatcher and control wired as the boards wire
 * them, sensors set by the test (the plant-level scenarios are in
 * tests/unit/control/test_protect_scenarios.c). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "km_app.h"
#include "km_fake_hal.h"
#include "km_test_support.h"

static void send(uint8_t cmd, const uint8_t *body, unsigned n)
{
    uint8_t f[64];
    kf_send_at(kf_world.now, f, kt_command(f, 0, cmd, body, n));
}

static void run_ms(uint32_t ms)
{
    assert_true(kf_run_for(ms * 1000u));
    assert_false(kf_world.spun);
}

/* Sends a command to servo 0 and returns its answer's value bytes (after
 * the command and address bytes) in out, their count, or -1 for a status
 * answer (then out[0] is the status byte), -2 for no answer. */
static int exchange(uint8_t cmd, const uint8_t *body, unsigned n, uint8_t *out)
{
    uint8_t junk[512];
    (void)kf_take_tx(junk, sizeof junk);
    send(cmd, body, n);
    run_ms(4);
    uint8_t a[64];
    const unsigned len = kf_take_tx(a, sizeof a);
    if (len == 0u) {
        return -2;
    }
    assert_true(len >= 6u);
    assert_int_equal(a[len - 1u], kt_sum(&a[2], len - 3u));
    if (a[3] == 2u) {
        out[0] = a[4];
        return -1;
    }
    memcpy(out, &a[6], len - 7u);
    return (int)(len - 7u);
}

static uint8_t ping(void)
{
    uint8_t s[4];
    assert_int_equal(exchange(0x01, NULL, 0, s), -1);
    return s[0];
}

static uint8_t read_u8(uint8_t addr)
{
    uint8_t v[8];
    assert_int_equal(exchange(0x02, &addr, 1, v), 1);
    return v[0];
}

static void write_u8(uint8_t addr, uint8_t value)
{
    const uint8_t b[2] = {addr, value};
    uint8_t v[8];
    assert_int_equal(exchange(0x03, b, 2, v), -2); /* response level 0: no answer */
}

static int ext(uint8_t addr, uint8_t *out)
{
    return exchange(0x7F, &addr, 1, out);
}

/* §5.2 0x3C, §4 bit 0, §5.4 0x64 = 5: a supply at 5.0 V (below 6 V) for
 * 3 s trips the voltage protection; while it holds, a move is refused (bit
 * 6) and 0x64 reads 5; 3 s after the supply is back it releases by itself
 * (0x33 = 0), bit 0 clears and 0x64 is 3 (armed). The fault log has the
 * trip with the supply it saw, then the release. */
static void test_s5_2_voltage_sag_trip_refuse_release_log(void **state)
{
    (void)state;
    kf_power_on();
    run_ms(50);
    assert_int_equal(ping(), 0x00);
    write_u8(0x64, 2);
    kf_world.voltage_mv = 5000;
    run_ms(2900);
    assert_int_equal(ping() & 0x01, 0);
    run_ms(200);
    assert_int_equal(ping(), 0x01);
    assert_int_equal(read_u8(0x36), 0x01);
    assert_int_equal(read_u8(0x64), 5);
    const uint8_t move[5] = {0x65, 0x84, 0x03, 0xF4, 0x01};
    uint8_t v[32];
    assert_int_equal(exchange(0x03, move, 5, v), -2);
    assert_int_equal(ping(), 0x41);           /* bit 6: refused; bit 0 still */
    assert_int_equal(kf_world.motor_mode, 0); /* 0x34 voltage 00: free */
    kf_world.voltage_mv = 7400;
    run_ms(2900);
    assert_int_equal(ping(), 0x01);
    run_ms(200);
    assert_int_equal(ping(), 0x00);
    assert_int_equal(read_u8(0x64), 3);

    assert_int_equal(ext(0x10, v), 7);
    assert_int_equal(v[0], 2);          /* events ever */
    assert_int_equal(v[4], 2);          /* held */
    assert_int_equal(v[5], 0);          /* kept from before a reset */
    assert_int_equal(ext(0x11, v), 18); /* newest: the release */
    assert_int_equal(v[4], 2);
    assert_int_equal(v[5], 0x01);
    assert_int_equal(ext(0x12, v), 18); /* the trip, with the supply it saw */
    assert_int_equal(v[4], 1);
    assert_int_equal(v[5], 0x01);
    assert_int_equal(v[8] | (v[9] << 8), 5000);
    const uint32_t t_trip = (uint32_t)v[0] | ((uint32_t)v[1] << 8) | ((uint32_t)v[2] << 16);
    assert_true(t_trip > 3000u && t_trip < 3300u); /* ms since boot: 50 + ~4 + 3000 */
    assert_int_equal(ext(0x13, v), 18);            /* not held yet: zeros, kind 0 */
    assert_int_equal(v[4], 0);
}

/* §5.2 0x33 bit 0 = 1: released only by a 0x36 write; a clear while the
 * supply is still low is refused (bit 6) and changes nothing; with the
 * supply back it stays active until cleared; the clear is logged as such. */
static void test_s5_2_release_by_command_clear_refused_while_active(void **state)
{
    (void)state;
    kf_power_on();
    run_ms(50);
    write_u8(0x33, 0x01);
    run_ms(50);
    kf_world.voltage_mv = 5000;
    run_ms(3100);
    assert_int_equal(ping(), 0x01);
    write_u8(0x36, 0x01);
    assert_int_equal(ping(), 0x41);
    assert_int_equal(read_u8(0x36), 0x01);
    kf_world.voltage_mv = 7400;
    run_ms(5000);
    assert_int_equal(ping(), 0x01); /* not released by itself */
    write_u8(0x36, 0x01);
    assert_int_equal(ping(), 0x00);
    assert_int_equal(read_u8(0x36), 0x00);
    uint8_t v[32];
    assert_int_equal(ext(0x11, v), 18);
    assert_int_equal(v[4], 3); /* cleared by command */
}

/* The fault log outlives a 0x02 restart: the entries are kept, one boot
 * older, and counted as kept; a simulated power-on starts it empty. */
static void test_fault_log_kept_across_restart_not_power_on(void **state)
{
    (void)state;
    kf_power_on();
    run_ms(50);
    kf_world.voltage_mv = 15000; /* above the fake product's 14 V */
    run_ms(3100);
    assert_int_equal(ping(), 0x01);
    const uint8_t restart[5] = {0x02, 0xE1, 0xE2, 0xE3, 0xE4};
    send(0x03, restart, 5);
    run_ms(100);
    uint8_t v[32];
    assert_int_equal(ext(0x10, v), 7);
    assert_int_equal(v[4], 1);
    assert_int_equal(v[5], 1); /* kept */
    assert_int_equal(ext(0x11, v), 18);
    assert_int_equal(v[4], 1);
    assert_int_equal(v[6], 1); /* one boot ago */
    assert_int_equal(v[8] | (v[9] << 8), 15000);
    kf_power_on();
    run_ms(50);
    assert_int_equal(ext(0x10, v), 7);
    assert_int_equal(v[0] | v[1] | v[2] | v[3], 0);
    assert_int_equal(v[4], 0);
}

/* §5.2 0x35 and §4 bit 4: an NTC reading -40.0 degC at boot (open) is a
 * temperature-sensor fault: 0x35 bit 2, status bit 4, torque on and moves
 * refused (bit 6), reads and writes still work, until the next restart. */
static void test_s5_2_self_test_fault_blocks_motion(void **state)
{
    (void)state;
    kf_power_on();
    run_ms(50);
    kf_world.temperature_c10 = -400;
    const uint8_t restart[5] = {0x02, 0xE1, 0xE2, 0xE3, 0xE4};
    send(0x03, restart, 5);
    run_ms(100);
    assert_int_equal(ping(), 0x10);
    assert_int_equal(read_u8(0x35), 0x04);
    write_u8(0x64, 2);
    assert_int_equal(ping(), 0x50);
    const uint8_t move[5] = {0x65, 0x84, 0x03, 0xF4, 0x01};
    uint8_t v[32];
    assert_int_equal(exchange(0x03, move, 5, v), -2);
    assert_int_equal(ping(), 0x50);
    assert_int_equal(kf_world.motor_mode, 0);
    const uint8_t delay[3] = {0x12, 100, 0}; /* writes still work */
    assert_int_equal(exchange(0x03, delay, 3, v), -2);
    assert_int_equal(ping(), 0x10);
    assert_int_equal(ext(0x11, v), 18);
    assert_int_equal(v[4], 4); /* hardware fault */
    assert_int_equal(v[5], 0x04);
    kf_world.temperature_c10 = 250;
    send(0x03, restart, 5);
    run_ms(100);
    assert_int_equal(ping(), 0x00); /* a sound NTC at the next boot */
}

static int16_t read_i16(uint8_t addr)
{
    uint8_t v[8];
    assert_int_equal(exchange(0x02, &addr, 1, v), 2);
    return (int16_t)(v[0] | (v[1] << 8));
}

static void write_i16(uint8_t addr, int16_t value)
{
    const uint8_t b[3] = {addr, (uint8_t)value, (uint8_t)((uint16_t)value >> 8)};
    uint8_t v[8];
    assert_int_equal(exchange(0x03, b, 3, v), -2);
}

static const uint8_t k_restart[5] = {0x02, 0xE1, 0xE2, 0xE3, 0xE4};

/* §5.2 0x35 bit 5, §5.4 0x64/0x65/0x6E (issue 18 item 2): the potentiometer
 * product booting with its horn resting on the -150.0 deg end stop (pushed
 * there by hand, past the +-135.0 deg travel) has no position fault, again
 * after a restart; it takes 0x64 = 2, 0x6E = -500 (into the stop: ends at
 * once, the shaft is past the travel), 0x6E = +500 (runs) and 0x6E = 0,
 * and a 0x65 back inside its travel, and gets there. */
static void test_s5_2_boot_on_end_stop_no_fault_moves_back(void **state)
{
    (void)state;
    kf_power_on();
    kf_world.pot_product = true;
    kf_use_plant(-1500);
    kf_boot(KM_RESET_POWER_ON);
    run_ms(50);
    for (int boot = 0; boot < 2; boot++) {
        assert_int_equal(ping(), 0x00);
        assert_int_equal(read_u8(0x35), 0x00);
        assert_int_equal(read_i16(0x46), -1500);
        send(0x03, k_restart, 5);
        run_ms(100);
    }
    write_u8(0x64, 2);
    assert_int_equal(ping(), 0x00);
    assert_int_equal(read_u8(0x64), 2);
    write_i16(0x6E, -500);
    run_ms(2);
    assert_int_equal(ping(), 0x00); /* taken (no bit 6), ended: past the travel (km_motor_mode.h) */
    write_i16(0x6E, 500);
    run_ms(2);
    assert_int_equal(ping(), 0x80); /* back toward the travel: running (bit 7), not refused */
    run_ms(200);
    write_i16(0x6E, 0);
    assert_int_equal(ping(), 0x00);
    const uint8_t move[5] = {0x65, 0x00, 0x00, 0xE8, 0x03}; /* 0.0 deg in 1000 ms */
    uint8_t v[8];
    assert_int_equal(exchange(0x03, move, 5, v), -2);
    assert_int_equal(ping() & 0x50, 0x00);
    run_ms(2000);
    const int16_t pos = read_i16(0x46);
    assert_true(pos >= -10 && pos <= 10);
    assert_int_equal(ping(), 0x00);
}

/* §5.2 0x35 bit 2, §4 bit 4 (issue 18 item 3): an NTC that opens while the
 * servo holds reads -40.0 degC; 500 ms later it is a temperature-sensor
 * fault, as at boot: status bit 4, the output let go, 0x64 = 0, moves
 * refused (bit 6), a fault-log entry (kind 4, 0x35 bits, the -40 degC it
 * read); the next boot with a sound NTC is clean. */
static void test_s5_2_ntc_opening_while_running_is_a_hardware_fault(void **state)
{
    (void)state;
    kf_power_on();
    run_ms(50);
    write_u8(0x64, 2);
    run_ms(100);
    assert_int_equal(kf_world.motor_mode, 2);
    kf_world.temperature_c10 = -400;
    run_ms(400);
    assert_int_equal(ping(), 0x00);
    assert_int_equal(read_u8(0x35), 0x00);
    run_ms(200);
    assert_int_equal(ping(), 0x10);
    assert_int_equal(read_u8(0x35), 0x04);
    assert_int_equal(read_u8(0x64), 0);
    assert_int_equal(kf_world.motor_mode, 0);
    const uint8_t move[5] = {0x65, 0x84, 0x03, 0xF4, 0x01};
    uint8_t v[32];
    assert_int_equal(exchange(0x03, move, 5, v), -2);
    assert_int_equal(ping(), 0x50);
    write_u8(0x64, 2);
    assert_int_equal(ping(), 0x50);
    assert_int_equal(kf_world.motor_mode, 0);
    assert_int_equal(ext(0x11, v), 18);
    assert_int_equal(v[4], 4); /* hardware fault */
    assert_int_equal(v[5], 0x04);
    assert_int_equal((int16_t)(v[12] | (v[13] << 8)), -400);
    kf_world.temperature_c10 = 250;
    send(0x03, k_restart, 5);
    run_ms(100);
    assert_int_equal(ping(), 0x00);
}

/* §5.2 0x34, §5.4 0x64 = 5 (issue 18 item 4): while the voltage protection
 * acts, 0x6E = 0 and 0x70 with its stop bit are accepted (no bit 6: the
 * output is stopped already), 0x6E = 500 is refused; with a hardware fault
 * latched the same, and 0x70's stop with brake (bit 1) brakes. */
static void test_s5_2_less_motion_accepted_while_protecting_or_faulted(void **state)
{
    (void)state;
    const uint8_t stop_free[6] = {0x70, 0x80, 0x00, 0x00, 0x00, 0x00};
    const uint8_t stop_brake[6] = {0x70, 0x82, 0x00, 0x00, 0x00, 0x00};
    uint8_t v[8];
    kf_power_on();
    run_ms(50);
    write_i16(0x6E, 200); /* under the motor-lead check's 300: the fake draws no current */
    run_ms(100);
    assert_int_equal(kf_world.motor_mode, 2);
    kf_world.voltage_mv = 5000;
    run_ms(3100);
    assert_int_equal(ping(), 0x01);
    assert_int_equal(kf_world.motor_mode, 0);
    write_i16(0x6E, 0);
    assert_int_equal(ping(), 0x01);
    assert_int_equal(exchange(0x03, stop_free, 6, v), -2);
    assert_int_equal(ping(), 0x01);
    assert_int_equal(exchange(0x03, stop_brake, 6, v), -2);
    assert_int_equal(ping(), 0x01);
    write_i16(0x6E, 500);
    assert_int_equal(ping(), 0x41);
    assert_int_equal(kf_world.motor_mode, 0); /* the protection frees (0x34 voltage 00) */
    kf_world.voltage_mv = 7400;
    run_ms(3200);
    assert_int_equal(ping(), 0x00);
    assert_true(kf_world.motor_mode != 2); /* released: nothing starts again */

    kf_world.temperature_c10 = -400;
    send(0x03, k_restart, 5);
    run_ms(100);
    assert_int_equal(ping(), 0x10);
    write_i16(0x6E, 0);
    assert_int_equal(ping(), 0x10);
    assert_int_equal(exchange(0x03, stop_brake, 6, v), -2);
    assert_int_equal(ping(), 0x10);
    assert_int_equal(kf_world.motor_mode, 1);
    assert_int_equal(exchange(0x03, stop_free, 6, v), -2);
    assert_int_equal(ping(), 0x10);
    assert_int_equal(kf_world.motor_mode, 0);
    write_i16(0x6E, 500);
    assert_int_equal(ping(), 0x50);
    assert_int_equal(kf_world.motor_mode, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s5_2_voltage_sag_trip_refuse_release_log),
        cmocka_unit_test(test_s5_2_release_by_command_clear_refused_while_active),
        cmocka_unit_test(test_fault_log_kept_across_restart_not_power_on),
        cmocka_unit_test(test_s5_2_self_test_fault_blocks_motion),
        cmocka_unit_test(test_s5_2_boot_on_end_stop_no_fault_moves_back),
        cmocka_unit_test(test_s5_2_ntc_opening_while_running_is_a_hardware_fault),
        cmocka_unit_test(test_s5_2_less_motion_accepted_while_protecting_or_faulted),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
