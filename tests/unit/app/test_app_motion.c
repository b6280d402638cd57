/* SPDX-License-Identifier: Apache-2.0 */
/* The servo moves, through the whole firmware: bytes on the simulated wire
 * -> parser -> dispatcher -> typed request -> control at the app's 1 kHz
 * tick -> the bridge of the fake board -> the servo plant (sim/plant,
 * kf_use_plant) -> sensors -> 0x46 read back over the bus. docs/protocol.md
 * §5.3 0x46/0x4D, §5.4 0x64/0x65/0x66/0x6E/0x70, §4 bit 7. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "km_app.h"
#include "km_fake_hal.h"
#include "km_test_support.h" /* kt_command: a §2 frame built from the rule */

static void send(uint8_t id, uint8_t cmd, const uint8_t *body, unsigned n)
{
    uint8_t f[64];
    kf_send_at(kf_world.now, f, kt_command(f, id, cmd, body, n));
}

static void run_ms(uint32_t ms)
{
    assert_true(kf_run_for(ms * 1000u));
    assert_false(kf_world.spun);
}

/* Reads a register of servo 0 over the bus; returns its value bytes as a
 * little-endian signed number (i16 or i32 by the answer's length). */
static int32_t read_reg(uint8_t addr, unsigned *len)
{
    uint8_t junk[512];
    (void)kf_take_tx(junk, sizeof junk);
    const uint8_t body[1] = {addr};
    send(0, 0x02, body, 1);
    run_ms(3); /* frame + 200 us answer delay + answer at 115200 */
    uint8_t a[64];
    const unsigned n = kf_take_tx(a, sizeof a);
    assert_true(n >= 8u);
    assert_int_equal(a[0], 0xF9);
    assert_int_equal(a[1], 0xF5);
    assert_int_equal(a[4], 0x02);
    assert_int_equal(a[5], addr);
    assert_int_equal(a[n - 1u], kt_sum(&a[2], n - 3u));
    const unsigned vlen = n - 7u;
    *len = vlen;
    if (vlen == 1u) {
        return a[6];
    }
    if (vlen == 2u) {
        return (int16_t)(a[6] | (a[7] << 8));
    }
    return (int32_t)((uint32_t)a[6] | ((uint32_t)a[7] << 8) | ((uint32_t)a[8] << 16) |
                     ((uint32_t)a[9] << 24));
}

static uint8_t ping_status(void)
{
    uint8_t junk[512];
    (void)kf_take_tx(junk, sizeof junk);
    send(0, 0x01, NULL, 0);
    run_ms(3);
    uint8_t a[16];
    const unsigned n = kf_take_tx(a, sizeof a);
    assert_int_equal(n, 6);
    return a[4];
}

/* §5.4: torque on (0x64 = 2), 0x65 to +45.0 deg in 500 ms; reads of 0x46
 * every 20 ms see it arrive within +-0.5 deg between 450 and 600 ms after
 * the command (the frames' own time included); bit 7 is set on the way and
 * clear after; 0x4D stops near 500 ms; then 0x66 back to 0 at 180 deg/s
 * arrives in about 250 ms + the acceleration. */
static void test_s5_4_move_45deg_500ms_over_the_bus(void **state)
{
    (void)state;
    kf_power_on();
    kf_use_plant(0);
    run_ms(20);
    unsigned len;
    assert_int_equal(read_reg(0x46, &len), 0);
    const uint8_t on[2] = {0x64, 0x02};
    send(0, 0x03, on, 2);
    run_ms(5);
    const uint8_t move[5] = {0x65, 0xC2, 0x01, 0xF4, 0x01}; /* 450, 500 ms */
    const uint32_t t0 = kf_world.now;
    send(0, 0x03, move, 5);
    run_ms(100);
    assert_true(ping_status() & 0x80); /* running */
    int32_t pos = read_reg(0x46, &len);
    assert_true(pos > 0 && pos < 450);
    uint32_t arrived = 0;
    while (kf_world.now - t0 < 1500000u) {
        run_ms(17);
        pos = read_reg(0x46, &len);
        if (!arrived && pos >= 445 && pos <= 455) {
            arrived = kf_world.now - t0;
        }
        assert_true(pos <= 455); /* no overshoot past the band */
    }
    print_message("0x65 +45.0 deg in 500 ms: within 0.5 deg after %u us, at %d\n", arrived, pos);
    assert_true(arrived >= 450000u && arrived <= 600000u);
    assert_true(pos >= 448 && pos <= 452);
    assert_int_equal(ping_status() & 0x80, 0); /* the motion ended */
    const int32_t rot = read_reg(0x4D, &len);
    assert_int_equal(len, 4);
    assert_true(rot >= 480 && rot <= 560);

    /* 0x66 back to 0 at 180 deg/s */
    const uint8_t back[5] = {0x66, 0x00, 0x00, 0xB4, 0x00};
    const uint32_t t1 = kf_world.now;
    send(0, 0x03, back, 5);
    arrived = 0;
    while (kf_world.now - t1 < 1000000u) {
        run_ms(17);
        pos = read_reg(0x46, &len);
        if (!arrived && pos >= -5 && pos <= 5) {
            arrived = kf_world.now - t1;
        }
    }
    print_message("0x66 to 0 at 180 deg/s: within 0.5 deg after %u us\n", arrived);
    assert_true(arrived >= 200000u && arrived <= 400000u);

    /* torque off: free, nothing holds it */
    const uint8_t off[2] = {0x64, 0x00};
    send(0, 0x03, off, 2);
    run_ms(5);
    assert_int_equal(kf_world.motor_mode, 0);
}

/* §5.4: with the torque off (0x64 = 0) a 0x65 is refused (bit 6 at the
 * next ping) and nothing moves. */
static void test_s5_4_move_refused_torque_off(void **state)
{
    (void)state;
    kf_power_on();
    kf_use_plant(100);
    const uint8_t off[2] = {0x64, 0x00};
    send(0, 0x03, off, 2);
    run_ms(5);
    (void)ping_status();
    const uint8_t move[5] = {0x65, 0xC2, 0x01, 0xF4, 0x01};
    send(0, 0x03, move, 5);
    run_ms(600);
    assert_int_equal(ping_status() & 0xC0, 0x40);
    unsigned len;
    assert_int_equal(read_reg(0x46, &len), 100);
}

/* docs/architecture.md ("Flash work and the bridge"): a commit (here 0x12, persisted)
 * while the bridge drives brakes it first, as a flash erase would stall the
 * CPU with the last PWM on the bridge; the next tick drives again and the
 * move still arrives. */
static void test_commit_while_driving_brakes_first(void **state)
{
    (void)state;
    kf_power_on();
    kf_use_plant(0);
    run_ms(20);
    const uint8_t on[2] = {0x64, 0x02};
    send(0, 0x03, on, 2);
    run_ms(5);
    const uint8_t move[5] = {0x65, 0x84, 0x03, 0xE8, 0x03}; /* 90.0 deg, 1000 ms */
    send(0, 0x03, move, 5);
    run_ms(300);
    assert_int_equal(kf_world.motor_mode, 2);
    const unsigned brakes = kf_world.motor_brakes;
    const uint8_t delay[3] = {0x12, 0x5E, 0x01}; /* 350 us */
    send(0, 0x03, delay, 3);
    run_ms(3);
    assert_int_equal(kf_world.motor_brakes, brakes + 1u);
    assert_int_equal(kf_world.motor_mode, 2); /* driving again */
    run_ms(1500);
    unsigned len;
    const int32_t pos = read_reg(0x46, &len);
    assert_true(pos >= 895 && pos <= 905);
    assert_int_equal(read_reg(0x12, &len), 350);
}

/* §5.4 0x6E over the bus (pot product, torque left armed: motor mode is
 * not gated by 0x64): PWM +400 turns the plant forward with bit 7 set, 0
 * stops it (idle output brake, bit 7 clear, the shaft at rest); then 0x70
 * runs -400 for 0.3 s and frees: 0x4D reads 300 +-2 ms. */
static void test_s5_4_motor_pwm_over_the_bus(void **state)
{
    (void)state;
    kf_power_on();
    kf_use_plant(-900);
    run_ms(20);
    unsigned len;
    const int32_t p0 = read_reg(0x46, &len);
    const uint8_t pwm[3] = {0x6E, 0x90, 0x01}; /* +400 */
    send(0, 0x03, pwm, 3);
    run_ms(300);
    assert_true(ping_status() & 0x80);
    assert_int_equal(kf_world.motor_mode, 2);
    const int32_t p1 = read_reg(0x46, &len);
    print_message("0x6E +400: %d -> %d x0.1 deg in ~300 ms\n", (int)p0, (int)p1);
    assert_true(p1 > p0 + 200);
    const uint8_t stop[3] = {0x6E, 0x00, 0x00};
    send(0, 0x03, stop, 3);
    run_ms(200);
    assert_int_equal(ping_status() & 0x80, 0);
    assert_int_equal(kf_world.motor_mode, 1); /* brake: 0x11 bit 1 */
    const int32_t p2 = read_reg(0x46, &len);
    run_ms(100);
    assert_int_equal(read_reg(0x46, &len), p2);

    const uint8_t timed[6] = {0x70, 0x11, 0x03, 0x00, 0x90, 0x01}; /* 0.3 s, PWM 400 reverse, then free */
    send(0, 0x03, timed, 6);
    run_ms(150);
    assert_true(ping_status() & 0x80);
    run_ms(300);
    assert_int_equal(ping_status() & 0xC0, 0);
    assert_int_equal(kf_world.motor_mode, 0);
    assert_true(read_reg(0x46, &len) < p2 - 200);
    const int32_t rot = read_reg(0x4D, &len);
    assert_true(rot >= 298 && rot <= 302);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s5_4_move_45deg_500ms_over_the_bus),
        cmocka_unit_test(test_s5_4_move_refused_torque_off),
        cmocka_unit_test(test_commit_while_driving_brakes_first),
        cmocka_unit_test(test_s5_4_motor_pwm_over_the_bus),
    };
    return cmocka_run_group_tests_name("app motion", tests, NULL, NULL);
}
