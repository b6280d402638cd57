/* SPDX-License-Identifier: Apache-2.0 */
/* Flash work and the bus (issue 21 goal 5; docs/store.md "Preparing in idle
 * time"): the real main loop over the fake board, with the STM32G0's flash
 * stalls modelled (a page erase stops the main loop for 22 ms, a
 * double-word program for 85 us; the RX interrupt keeps filling the RX
 * queue). A blank store is formatted while the bus is silent, not inside
 * the first saved setting; a persisted write and a user data reset inside
 * back-to-back traffic at 1 Mbit/s lose no frame (docs/protocol.md §5:
 * 0x03 user data reset, 0x10 baud, 0x13 a persisted register). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "km_app.h"
#include "km_fake_hal.h"
#include "km_parser.h"
#include "km_test_support.h"

/* km_app.c's diagnostics for the line-rate benchmark (not in km_app.h). */
const km_parser_stats_t *km_app_parser_stats(void);
uint32_t km_app_rx_dropped(void);

#define G0_ERASE_US 22000u /* RM0444 page erase, the short end of 22-40 ms */
#define G0_PROGRAM_US 85u  /* one double word */
#define BUS_QUIET_MS 100u  /* more than the app's 50 ms silence rule */

static void run_ms(uint32_t ms)
{
    assert_true(kf_run_for(ms * 1000u));
    assert_false(kf_world.spun);
}

/* Puts a command frame on the wire from `at`; returns the tick of its last byte. */
static uint32_t send_at(uint32_t at, uint8_t id, uint8_t cmd, const uint8_t *body, unsigned n)
{
    uint8_t f[64];
    const unsigned len = kt_command(f, id, cmd, body, n);
    kf_send_at(at, f, len);
    return kf_world.rx[kf_world.rx_n - 1u].tick;
}

/* Microseconds from a ping's last byte to its answer's first byte. */
static uint32_t ping_latency(uint32_t at)
{
    const unsigned before = kf_world.tx_n;
    const uint32_t end = send_at(at, 0x00, 0x01, NULL, 0);
    run_ms(100);                                 /* long enough to see one delayed by erases */
    assert_int_equal(kf_world.tx_n - before, 6); /* F9 F5 00 02 status sum */
    return kf_tx_tick(before) - end;
}

static void power_on_g0(void)
{
    kf_power_on();
    kf_world.erase_us = G0_ERASE_US;
    kf_world.program_us = G0_PROGRAM_US;
}

/* A blank store is formatted in bus silence; the first saved setting then
 * costs one program (one 8-byte dense delta) and no erase, and a ping
 * 2.5 ms after it is answered as soon as one in a quiet bus. On the code
 * before this change the write did both page erases (44 ms of stall) and
 * the ping's answer came that much late. */
static void test_first_saved_setting_costs_one_program_and_ping_is_on_time(void **state)
{
    (void)state;
    power_on_g0();
    const uint32_t quiet_latency = ping_latency(kf_world.now);
    run_ms(BUS_QUIET_MS);
    const uint32_t erases = kf_world.nor.count.erases;
    const uint32_t programs = kf_world.nor.count.programs;
    const uint8_t write[] = {0x13, 0xE7, 0x03}; /* 0x13 = 999 */
    const uint32_t write_end = send_at(kf_world.now, 0x00, 0x03, write, sizeof write);
    const uint32_t latency = ping_latency(write_end + 2500u);
    print_message("ping latency: %u us in a quiet bus, %u us 2.5 ms after the first saved setting\n",
                  (unsigned)quiet_latency, (unsigned)latency);
    assert_true(latency <= quiet_latency + 200u);
    assert_int_equal(erases, 2); /* both pages, before any write */
    assert_int_equal(kf_world.nor.count.erases, erases);
    assert_int_equal(kf_world.nor.count.programs - programs, 1);
    /* durable: after a restart the store loads (0x7F 0x01 = 0: loaded) */
    kf_send_hex("F9 FF 00 07 03 02 E1 E2 E3 E4 69");
    run_ms(20);
    uint8_t got[64];
    (void)kf_take_tx(got, sizeof got);
    kf_send_hex("F9 FF 00 03 7F 01 7C");
    run_ms(5);
    assert_int_equal(kf_take_tx(got, sizeof got), 8);
    assert_int_equal(got[6], 0x00);
}

/* Idle flash work waits for bus silence: while frames (for another servo)
 * keep coming the blank store is not touched; once the bus is quiet it is
 * formatted. */
static void test_store_formatting_waits_for_bus_silence(void **state)
{
    (void)state;
    power_on_g0();
    const uint8_t read[] = {0x38, 0x02};
    uint32_t at = kf_world.now;
    for (int i = 0; i < 60; i++) { /* one frame every 5 ms for 300 ms */
        (void)send_at(at, 0x07, 0x02, read, sizeof read);
        at += 5000u;
    }
    run_ms(300);
    assert_int_equal(kf_world.nor.count.erases, 0);
    assert_int_equal(km_app_parser_stats()->frames_ok, 60);
    run_ms(BUS_QUIET_MS);
    assert_int_equal(kf_world.nor.count.erases, 2);
}

/* `n` back-to-back reads for another servo, with one frame for this servo
 * (cmd, body) in the middle. */
static void stream_with(unsigned n, uint8_t cmd, const uint8_t *body, unsigned len)
{
    const uint8_t read[] = {0x38, 0x02};
    for (unsigned i = 0; i < n; i++) {
        if (i == n / 2u) {
            (void)send_at(kf_world.now, 0x00, cmd, body, len);
        }
        (void)send_at(kf_world.now, 0x07, 0x02, read, sizeof read);
    }
}

/* With the board option that prepares the store in every session (the
 * stored baud of 1 Mbit/s means the session after the restart starts from a
 * loaded store): one persisted write and one user data reset inside
 * back-to-back traffic at 1 Mbit/s, no frame lost, no byte dropped, and no
 * erase while the traffic runs. On the code before this change the write's
 * first commit erased a page (22 ms: 2,200 byte times at 1 Mbit/s) with a
 * 128-byte RX queue. */
static void test_persisted_write_and_reset_in_1mbit_traffic_lose_no_frame(void **state)
{
    (void)state;
    power_on_g0();
    kf_world.prepare_each_boot = true;
    const uint8_t baud[] = {0x10, 0x10, 0x27}; /* 10000 x 100 baud */
    (void)send_at(kf_world.now, 0x00, 0x03, baud, sizeof baud);
    run_ms(80);
    kf_send_hex("F9 FF 00 07 03 02 E1 E2 E3 E4 69"); /* restart: 1 Mbit/s from now */
    run_ms(20);
    assert_int_equal(kf_world.baud, 1000000u);
    run_ms(BUS_QUIET_MS); /* the new session prepares its page in this silence */
    const uint32_t erases = kf_world.nor.count.erases;
    const uint32_t frames = km_app_parser_stats()->frames_ok;
    const uint8_t write[] = {0x13, 0xE7, 0x03};
    stream_with(300, 0x03, write, sizeof write);
    const uint8_t reset[] = {0x03, 0x01}; /* level 1 */
    stream_with(300, 0x03, reset, sizeof reset);
    run_ms(60); /* 602 frames of 7-9 bytes: about 42 ms at 1 Mbit/s */
    print_message("frames delivered %u of 602, bytes dropped %u, erases during the traffic %u\n",
                  (unsigned)(km_app_parser_stats()->frames_ok - frames), (unsigned)km_app_rx_dropped(),
                  (unsigned)(kf_world.nor.count.erases - erases));
    assert_int_equal(km_app_parser_stats()->frames_ok - frames, 602);
    assert_int_equal(km_app_rx_dropped(), 0);
    assert_int_equal(kf_world.nor.count.erases, erases);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_first_saved_setting_costs_one_program_and_ping_is_on_time),
        cmocka_unit_test(test_store_formatting_waits_for_bus_silence),
        cmocka_unit_test(test_persisted_write_and_reset_in_1mbit_traffic_lose_no_frame),
    };
    return cmocka_run_group_tests_name("app_flash", tests, NULL, NULL);
}
