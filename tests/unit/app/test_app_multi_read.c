/* SPDX-License-Identifier: Apache-2.0 */
/* Multi-ID read 0x82 through the real main loop over bytes in virtual time
 * (docs/protocol-decisions.md "Multi-ID read 0x82"; docs/protocol.md §3, §7):
 * the answer of a listed servo starts response_delay + j x slot after the
 * frame's last byte, j its position in the list, on the wire; a list longer
 * than a frame can carry is no frame. Prints the time to read 0x46 from 20
 * servos at 1 Mbit/s with one 0x82 and with 20 single reads (one servo
 * stands in for each list position / each read: the wire time is the same). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "km_app.h"
#include "km_fake_hal.h"
#include "km_test_support.h" /* kt_hex, kt_sum, kt_slot_us: the §2/§3 rules written out */

static uint8_t s_tx[KF_TX_MAX];

static void run_ms(uint32_t ms)
{
    assert_true(kf_run_for(ms * 1000u));
    assert_false(kf_world.spun);
}

static void boot(void)
{
    kf_power_on();
    run_ms(2);
    assert_int_equal(kf_take_tx(s_tx, sizeof s_tx), 0);
}

/* The frame's bytes on the wire from now; returns the tick of its last byte
 * (the frame end the servo stamps). */
static uint32_t send(uint8_t id, uint8_t cmd, const uint8_t *body, unsigned n)
{
    uint8_t f[300];
    kf_send_at(kf_world.now, f, kt_command(f, id, cmd, body, n));
    return kf_world.rx[kf_world.rx_n - 1u].tick;
}

/* 0x82 of `addr` naming `count` IDs, ours (0) at position `pos`, the rest
 * 1, 2, ... */
static uint32_t send_mread(uint8_t addr, unsigned count, unsigned pos)
{
    uint8_t body[KM_BODY_MAX];
    body[0] = addr;
    uint8_t other = 1;
    for (unsigned j = 0; j < count; j++) {
        body[1 + j] = j == pos ? 0u : other++;
    }
    return send(KM_ID_BROADCAST, 0x82, body, 1u + count);
}

/* One whole read answer from ID 0 for `addr` since the last look; returns
 * the index (since power-on) of its first byte. */
static unsigned take_read_answer(uint8_t addr)
{
    const unsigned first = kf_world.tx_n;
    const unsigned n = kf_take_tx(s_tx, sizeof s_tx);
    if (n < 7u || s_tx[0] != 0xF9 || s_tx[1] != 0xF5 || s_tx[2] != 0 || n != 4u + s_tx[3] ||
        s_tx[4] != 0x02 || s_tx[5] != addr || s_tx[n - 1u] != kt_sum(&s_tx[2], n - 3u)) {
        fail_msg("not one read answer for 0x%02X (%u bytes)", addr, n);
    }
    return first - n;
}

/* Writes u16 `v` to `addr` of ID 0 (response level 0: no answer). */
static void write_u16(uint8_t addr, uint16_t v)
{
    const uint8_t body[] = {addr, (uint8_t)v, (uint8_t)(v >> 8)};
    send(0, 0x03, body, sizeof body);
    run_ms(5);
}

/* 0x10 = 10000 and a restart: the bus at 1 Mbit/s. */
static void go_1mbit(void)
{
    write_u16(0x10, 10000);
    kf_send_hex("F9 FF 00 07 03 02 E1 E2 E3 E4 69");
    run_ms(20);
    assert_int_equal(kf_world.baud, 1000000);
}

/* "Multi-ID read 0x82": 20 IDs, this servo at positions 0, 1, 2, 7, 19:
 * its answer's first byte leaves 200 + j x 1129 us (0x46: 11-byte longest
 * answer + 2 guard bytes at 115200) after the frame's last byte, within
 * the main loop's few microseconds. */
static void test_mread_slot_start_on_the_wire(void **state)
{
    (void)state;
    boot();
    static const unsigned positions[] = {0, 1, 2, 7, 19};
    const uint32_t slot = kt_slot_us(11, 115200);
    assert_int_equal(slot, 1129);
    for (unsigned k = 0; k < sizeof positions / sizeof positions[0]; k++) {
        const uint32_t end = send_mread(0x46, 20, positions[k]);
        run_ms(30);
        const unsigned first = take_read_answer(0x46);
        const uint32_t due = end + 200u + positions[k] * slot;
        const uint32_t start = kf_tx_tick(first);
        if (start < due || start > due + 5u) {
            fail_msg("position %u: answer at +%u us, due at +%u", positions[k], (unsigned)(start - end),
                     (unsigned)(due - end));
        }
    }
}

/* The same at 1 Mbit/s (slot 130 us) and with 0x12 = 500 us. */
static void test_mread_slot_start_1mbit(void **state)
{
    (void)state;
    boot();
    go_1mbit();
    write_u16(0x12, 500);
    assert_int_equal(kt_slot_us(11, 1000000), 130);
    for (unsigned pos = 0; pos < 20u; pos += 19u) {
        const uint32_t end = send_mread(0x46, 20, pos);
        run_ms(10);
        const uint32_t start = kf_tx_tick(take_read_answer(0x46));
        const uint32_t due = end + 500u + pos * 130u;
        assert_true(start >= due && start <= due + 5u);
    }
}

/* "Answer slots on emulated buses": an emulated board's slot floor
 * (km_app_set_bus_floors after km_app_init) reaches the dispatcher: with
 * 5 ms, position 2 answers 200 + 2 x 5000 us after the frame. */
static void test_mread_slot_floor_from_the_board(void **state)
{
    (void)state;
    kf_power_on();
    kf_world.slot_floor_us = 5000u;
    kf_boot(KM_RESET_POWER_ON);
    run_ms(2);
    const uint32_t end = send_mread(0x46, 3, 2);
    run_ms(30);
    const uint32_t start = kf_tx_tick(take_read_answer(0x46));
    assert_true(start >= end + 200u + 2u * 5000u && start <= end + 200u + 2u * 5000u + 5u);
}

/* The longest list: 249 IDs (length 252), ours last: slot 248, 280 ms
 * after the frame at 115200. One ID more needs length 253 (§2: at most
 * 252): the parser takes no frame from those bytes, nothing answers, and
 * the servo answers the next frame. */
static void test_mread_longest_list_and_one_more(void **state)
{
    (void)state;
    boot();
    const uint32_t end = send_mread(0x46, 249, 248); /* 256 bytes: 22 ms */
    run_ms(330);
    const uint32_t start = kf_tx_tick(take_read_answer(0x46));
    assert_true(start >= end + 200u + 248u * 1129u && start <= end + 200u + 248u * 1129u + 5u);

    uint8_t f[KM_FRAME_MAX + 8];
    f[0] = 0xF9;
    f[1] = 0xFF;
    f[2] = KM_ID_BROADCAST;
    f[3] = 253; /* 0x82, the address, 250 IDs, the checksum */
    f[4] = 0x82;
    f[5] = 0x46;
    for (unsigned j = 0; j < 250u; j++) {
        f[6 + j] = (uint8_t)(250u - j); /* 250 .. 1, no room for ID 0 */
    }
    f[6 + 249] = 0; /* ours last */
    f[256] = kt_sum(&f[2], 254);
    kf_send_at(kf_world.now, f, 257);
    run_ms(400);
    assert_int_equal(kf_take_tx(s_tx, sizeof s_tx), 0);
    kf_send_hex("F9 FF 00 02 01 FC");
    run_ms(5);
    assert_int_equal(kf_take_tx(s_tx, sizeof s_tx), 6);
}

/* The figure: reading 0x46 (a 9-byte answer) from 20 servos at 1 Mbit/s,
 * from the first request bit to the last answer bit, the master sending
 * the next request the moment the last answer has ended:
 *   one 0x82:   (20 + 7) bytes out, then 0x12 + 19 x slot(11 B) + 9 bytes
 *             = 270 + 200 + 19 x 130 + 90 = 3030 us
 *   20 reads:  20 x (7 bytes out + 0x12 + 9 bytes back)
 *             = 20 x (70 + 200 + 90) = 7200 us
 * Printed as measured on the wire here; asserted only that every answer
 * came (a figure, not a timing pass/fail: the slot starts are tested above). */
static void test_mread_figure_20_servos_1mbit(void **state)
{
    (void)state;
    boot();
    go_1mbit();
    const uint32_t byte_us = kf_byte_us();
    assert_int_equal(byte_us, 10);

    send_mread(0x46, 20, 19);
    /* a received byte is stamped when its stop bit is in: its first bit
     * went one byte time earlier */
    const uint32_t first_bit = kf_world.rx[kf_world.rx_n - 27u].tick - byte_us;
    run_ms(10);
    const unsigned a = take_read_answer(0x46);
    const unsigned alen = kf_world.tx_n - a;
    const uint32_t mread_us = kf_tx_tick(a + alen - 1u) + byte_us - first_bit;

    const uint8_t adr = 0x46;
    uint32_t reads_us = 0;
    for (unsigned i = 0; i < 20u; i++) {
        send(0, 0x02, &adr, 1);
        const uint32_t start = kf_world.rx[kf_world.rx_n - 7u].tick - byte_us;
        const unsigned want = a + alen * (i + 2u);
        /* the master waits for the answer's last stop bit, then sends */
        for (unsigned t = 0; t < 1000u && (kf_world.tx_n < want || kf_world.tx_buf != NULL); t++) {
            assert_true(kf_run_for(1u));
        }
        assert_int_equal(kf_world.tx_n, want);
        reads_us += kf_tx_tick(want - 1u) + byte_us - start;
    }
    print_message("0x82 figure, 20 servos, 0x46, 1 Mbit/s, 0x12 = 200 us (virtual time): "
                  "one 0x82 %u us (formula 3030), 20 single reads %u us (formula 7200)\n",
                  (unsigned)mread_us, (unsigned)reads_us);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mread_slot_start_on_the_wire),
        cmocka_unit_test(test_mread_slot_start_1mbit),
        cmocka_unit_test(test_mread_slot_floor_from_the_board),
        cmocka_unit_test(test_mread_longest_list_and_one_more),
        cmocka_unit_test(test_mread_figure_20_servos_1mbit),
    };
    return cmocka_run_group_tests_name("app_multi_read", tests, NULL, NULL);
}
