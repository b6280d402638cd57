/* SPDX-License-Identifier: Apache-2.0 */
/* The real main loop (firmware/app/km_app.c: RX queue, parser, dispatcher,
 * answer timer, store on the NOR simulator, control tick, watchdog) driven
 * over a simulated wire in virtual time (tests/support/km_fake_hal.h).
 * These are the defects issue 13 found in the glue between parser, app loop
 * and dispatcher, each with the bytes that showed it; each test fails on the
 * code before its fix. docs/protocol.md sections and docs/protocol-decisions.md
 * headings are named per test. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "km_app.h"
#include "km_fake_hal.h"
#include "km_test_support.h" /* kt_hex, kt_sum: the §2 rules written out for tests */

/* ---- wire helpers ----------------------------------------------------------- */

typedef struct {
    uint8_t b[8192];
    unsigned n;
} wire_t;

static void send_frame(uint8_t id, uint8_t cmd, const uint8_t *body, unsigned n)
{
    uint8_t f[300];
    kf_send_at(kf_world.now, f, kt_command(f, id, cmd, body, n));
}

static void take(wire_t *w)
{
    w->n = kf_take_tx(w->b, sizeof w->b);
}

static void run_ms(uint32_t ms)
{
    assert_true(kf_run_for(ms * 1000u));
    assert_false(kf_world.spun);
}

/* Everything the servo sent since the last look equals `hex`. */
static void answered(const char *hex)
{
    uint8_t want[512];
    const unsigned n = kt_hex(hex, want, sizeof want);
    wire_t w;
    take(&w);
    if (w.n != n || memcmp(w.b, want, n) != 0) {
        char got[3 * 64 + 1] = {0};
        for (unsigned i = 0; i < w.n && i < 64; i++) {
            static const char hx[] = "0123456789ABCDEF";
            got[3 * i] = hx[w.b[i] >> 4];
            got[3 * i + 1] = hx[w.b[i] & 15];
            got[3 * i + 2] = ' ';
        }
        fail_msg("servo sent [%s] (%u bytes), wanted [%s]", got, w.n, hex);
    }
}

static void nothing_sent(void)
{
    wire_t w;
    take(&w);
    assert_int_equal(w.n, 0);
}

/* Sends hex, runs `ms`, checks the answer. */
static void exchange(const char *hex, uint32_t ms, const char *want)
{
    kf_send_hex(hex);
    run_ms(ms);
    if (want) {
        answered(want);
    } else {
        nothing_sent();
    }
}

static void ping_is(uint8_t id, uint8_t status)
{
    uint8_t want[6] = {0xF9, 0xF5, id, 0x02, status, 0};
    want[5] = kt_sum(&want[2], 3);
    send_frame(id, 0x01, NULL, 0);
    run_ms(30); /* a ping and its answer take 12.7 ms at 9600 baud */
    wire_t w;
    take(&w);
    assert_int_equal(w.n, 6);
    assert_memory_equal(w.b, want, 6);
}

static void boot(void)
{
    kf_power_on();
    run_ms(2);
    nothing_sent();
}

/* Every frame on the wire is whole and has a valid checksum. */
static unsigned wire_frames_ok(const wire_t *w)
{
    unsigned frames = 0;
    for (unsigned i = 0; i < w->n;) {
        if (i + 4u > w->n || w->b[i] != 0xF9 || w->b[i + 1] != 0xF5) {
            return 0;
        }
        const unsigned len = w->b[i + 3];
        if (i + 4u + len > w->n || w->b[i + 3 + len] != kt_sum(&w->b[i + 2], len + 1u)) {
            return 0;
        }
        i += 4u + len;
        frames++;
    }
    return frames;
}

/* ---- 1: restart is at once (§3; vendor 3.1.2) ------------------------------ */

/* A restart and an ID write in one write: after the restart the servo still
 * answers on ID 0; the ID write after the restart never ran (not committed). */
static void test_s3_restart_at_once_nothing_after_it_runs(void **state)
{
    (void)state;
    boot();
    const unsigned programs_before = kf_world.nor.count.programs;
    /* Both frames already received when the loop gets to them (as a UART
     * FIFO, DMA or host-sim's socket hands them over): one tick for all. */
    uint8_t b[32];
    const unsigned n = kt_hex("F9 FF 00 07 03 02 E1 E2 E3 E4 69 F9 FF 00 04 03 0F 05 E4", b, sizeof b);
    kf_send_burst_at(kf_world.now, b, n);
    run_ms(20);
    nothing_sent();
    assert_int_equal(kf_world.software_resets, 1);
    assert_int_equal(kf_world.nor.count.programs, programs_before);
    ping_is(0, 0x00);
    exchange("F9 FF 05 02 01 F7", 5, NULL); /* nobody is ID 5 */
}

/* ---- 2: the loop never waits on the bus ------------------------------------ */

/* A ping and a restart in one write: the ping is answered, then the servo
 * restarts, and answers again after. (host-sim hung here for ever.) */
static void test_s3_restart_after_pending_answer(void **state)
{
    (void)state;
    boot();
    exchange("F9 FF 00 02 01 FC F9 FF 00 07 03 02 E1 E2 E3 E4 69", 20, "F9 F5 00 02 00 FD");
    assert_int_equal(kf_world.software_resets, 1);
    assert_int_equal(kf_world.watchdog_resets, 0);
    ping_is(0, 0x00);
}

/* Decision "Super-ID answer slots": ID 250 at 9600 baud reading 0x0A (16 B
 * answers) starts its answer 250 slots of 24 byte times (6.25 s) after the
 * frame. A restart queued behind it waits for the answer while the control
 * tick and the watchdog (500 ms) go on: no watchdog reset, no spin. */
static void test_s3_restart_waits_seconds_for_super_id_slot(void **state)
{
    (void)state;
    boot();
    exchange("F9 FF 00 05 03 10 60 00 87", 5, NULL);        /* 0x10 = 96: 9600 baud */
    exchange("F9 FF 00 04 03 0F FA EF", 5, NULL);           /* ID 250 */
    exchange("F9 FF FA 07 03 02 E1 E2 E3 E4 6F", 20, NULL); /* restart: 9600 from now */
    assert_int_equal(kf_world.baud, 9600);
    const uint32_t sent = kf_world.now;
    kf_send_hex("F9 FF FD 03 02 0A F3 F9 FF FA 07 03 02 E1 E2 E3 E4 6F");
    run_ms(7000);
    /* slot = ceil((7 + 16 + 2) x 10 bits x 1e6 / 9600) = 26042 us; ID 250
     * starts 200 + 250 x 26042 us = 6.51 s after the read's last byte. */
    assert_int_equal(kf_world.watchdog_resets, 0);
    assert_int_equal(kf_world.software_resets, 2);
    wire_t w;
    take(&w);
    assert_int_equal(wire_frames_ok(&w), 1);
    assert_int_equal(w.b[2], 250);
    assert_int_equal(w.b[4], 0x02);
    assert_int_equal(w.b[5], 0x0A);
    assert_memory_equal(&w.b[6], "KM-FAKE-BOARD", 13);
    const uint32_t read_end = sent + 6250u; /* its 7th byte: 6 x 1041.7 us later */
    const uint32_t due = read_end + 200u + 250u * 26042u;
    assert_true(kf_tx_tick(kf_world.tx_n - w.n) >= due);
    assert_true(kf_tx_tick(kf_world.tx_n - w.n) <= due + 100u);
    ping_is(250, 0x00);
}

/* ---- 3: no stale bit 5 after an ID change (§4 Decision) --------------------- */

static void test_s4_no_stale_bit5_after_id_change(void **state)
{
    (void)state;
    boot();
    exchange("F9 FF 05 02 01 08", 5, NULL);       /* bad checksum, ID 5, we are 0 */
    exchange("F9 FF 00 04 03 0F 05 E4", 5, NULL); /* ID becomes 5 */
    exchange("F9 FF 05 02 01 F7", 5, "F9 F5 05 02 00 F8");
    exchange("F9 FF 09 02 01 0C", 5, NULL); /* bad checksum, ID 9: not ours */
    exchange("F9 FF 05 02 01 F7", 5, "F9 F5 05 02 00 F8");
}

/* A bad frame for our ID still sets bit 5, once. */
static void test_s4_bad_checksum_for_our_id_reported_once(void **state)
{
    (void)state;
    boot();
    exchange("F9 FF 00 02 01 03", 5, NULL);
    exchange("F9 FF 00 02 01 FC", 5, "F9 F5 00 02 20 DD");
    exchange("F9 FF 00 02 01 FC", 5, "F9 F5 00 02 00 FD");
}

/* ---- 4: one life cycle for bits 5 and 6 -------------------------------------- */

/* (a) At response level 1 a checksum error, then a good write: the write
 * answers 00 (it worked); the next ping reports the checksum error once. */
static void test_s4_good_write_after_checksum_error_level1(void **state)
{
    (void)state;
    boot();
    exchange("F9 FF 00 04 03 11 0A DD", 5, "F9 F5 00 02 00 FD"); /* level 1 */
    exchange("F9 FF 00 02 01 03", 5, NULL);
    exchange("F9 FF 00 05 03 13 E8 03 F9", 5, "F9 F5 00 02 00 FD");
    exchange("F9 FF 00 02 01 FC", 5, "F9 F5 00 02 20 DD");
    exchange("F9 FF 00 02 01 FC", 5, "F9 F5 00 02 00 FD");
}

/* (b) At level 0 a failed write, a read in between (its answer carries no
 * status byte), then a ping: the failure is still reported. */
static void test_s4_failed_write_survives_a_read_level0(void **state)
{
    (void)state;
    boot();
    exchange("F9 FF 00 05 03 13 E9 03 F8", 5, NULL);
    exchange("F9 FF 00 03 02 13 E7", 5, "F9 F5 00 05 02 13 E8 03 FA");
    exchange("F9 FF 00 02 01 FC", 5, "F9 F5 00 02 40 BD");
    exchange("F9 FF 00 02 01 FC", 5, "F9 F5 00 02 00 FD");
}

/* ---- 9: 0x83 naming an address it does not allow (§4: bit 5) ------------- */

static void test_s4_multi_id_unsupported_address_is_bit5(void **state)
{
    (void)state;
    boot();
    exchange("F9 FF 00 04 03 0F 05 E4", 5, NULL); /* ID 5 */
    exchange("F9 FF FE 07 83 13 02 05 00 00 5D", 5, NULL);
    exchange("F9 FF 05 02 01 F7", 5, "F9 F5 05 02 20 D8");
    exchange("F9 FF 05 02 01 F7", 5, "F9 F5 05 02 00 F8");
}

/* ---- 8: the gap (docs/protocol-decisions.md "Inter-byte gap") --------------- */

/* With the delivery floor at 0 (a real UART), a frame whose bytes stop for
 * more than max(10 byte times, 1 ms) is dropped and the next one answered;
 * a pause under the gap is not a cut. */
static void test_s7_gap_real_rule(void **state)
{
    (void)state;
    boot();
    const uint8_t ping[] = {0xF9, 0xFF, 0x00, 0x02, 0x01, 0xFC};
    kf_send_at(kf_world.now, ping, 3);
    kf_send_at(kf_world.now + 3u * kf_byte_us() + 1200u, &ping[3], 3); /* 1.2 ms pause */
    run_ms(10);
    nothing_sent();
    assert_int_equal(wire_frames_ok(&(wire_t){0}), 0);
    kf_send_at(kf_world.now, ping, 3);
    kf_send_at(kf_world.now + 3u * kf_byte_us() + 800u, &ping[3], 3); /* 0.8 ms: kept */
    run_ms(10);
    answered("F9 F5 00 02 00 FD");
    ping_is(0, 0x00); /* the dropped frame left nothing behind */
}

/* docs/benchmarks.md "Per byte": the receive interrupt asks for a main-loop
 * pass (km_hal_wake) on a frame's last byte only, not on the bytes before
 * it; frames for another servo and another servo's answer (§2), so no
 * answer timer wakes the loop either. */
static void test_rx_wakes_main_loop_at_frame_end_only(void **state)
{
    (void)state;
    boot();
    static const char *const frames[] = {
        "F9 FF 05 04 02 38 02 BA",    /* read for servo 5 */
        "F9 F5 05 04 00 10 27 BF",    /* servo 5's answer */
        "F9 FF 07 05 03 2A 01 02 C3", /* write for servo 7 */
    };
    for (unsigned f = 0; f < 3u; f++) {
        uint8_t b[16];
        const unsigned n = kt_hex(frames[f], b, sizeof b);
        const unsigned wakes = kf_world.wakes;
        const uint32_t at = kf_world.now + 100u;
        kf_send_at(at, b, n); /* back to back at line rate: byte i at at + i byte times */
        run_ms(3);
        assert_int_equal(kf_world.wakes - wakes, 1u);
        const uint32_t last = at + (n - 1u) * kf_byte_us();  /* the last byte's tick */
        assert_true(kf_world.wake_at - last < kf_byte_us()); /* woken by that byte */
    }
    nothing_sent();
}

/* An emulated board's floor (20 ms by default there) keeps a frame whose
 * bytes the host delivered 5 ms apart. */
static void test_s7_gap_delivery_floor(void **state)
{
    (void)state;
    kf_power_on();
    kf_world.gap_floor_us = 20000u;
    kf_boot(KM_RESET_POWER_ON); /* the board hands the floor over at boot */
    const uint8_t ping[] = {0xF9, 0xFF, 0x00, 0x02, 0x01, 0xFC};
    for (int i = 0; i < 4; i++) { /* every time, not every other time */
        kf_send_at(kf_world.now, ping, 3);
        kf_send_at(kf_world.now + 8000u, &ping[3], 3);
        run_ms(30);
        answered("F9 F5 00 02 00 FD");
    }
}

/* ---- 13: the watchdog runs before the store is touched ------------------------ */

/* Item 13: the watchdog starts before the store is mounted, so a hang on
 * bad flash resets the MCU instead of hanging for ever. */
static void test_wdt_started_before_store_mount(void **state)
{
    (void)state;
    boot();
    assert_true(kf_world.wdt_running);
    assert_true(kf_world.nor.count.reads > kf_world.reads_at_boot); /* the mount read flash */
    assert_int_equal(kf_world.reads_at_wdt_start, kf_world.reads_at_boot);
}

/* ---- 13: reset cause and fall-back baud in the extension space --------------- */

/* docs/protocol-decisions.md "Extension command 0x7F": 0x02 reset cause. */
static void test_ext_reset_cause(void **state)
{
    (void)state;
    boot();
    exchange("F9 FF 00 03 7F 02 7B", 5, "F9 F5 00 04 7F 02 00 7A"); /* power-on */
    exchange("F9 FF 00 07 03 02 E1 E2 E3 E4 69", 20, NULL);
    exchange("F9 FF 00 03 7F 02 7B", 5, "F9 F5 00 04 7F 02 02 78"); /* software */
}

/* 0x01 where the user data came from: blank flash, then loaded. */
static void test_ext_userdata_source(void **state)
{
    (void)state;
    boot();
    exchange("F9 FF 00 03 7F 01 7C", 5, "F9 F5 00 04 7F 01 02 79"); /* blank */
    exchange("F9 FF 00 05 03 13 E7 03 FA", 5, NULL);                /* a commit */
    exchange("F9 FF 00 07 03 02 E1 E2 E3 E4 69", 20, NULL);
    exchange("F9 FF 00 03 7F 01 7C", 5, "F9 F5 00 04 7F 01 00 7B"); /* loaded */
    exchange("F9 FF 00 03 02 0D ED", 5, "F9 F5 00 02 20 DD");       /* 0x0D: reserved again */
}

/* ---- 15: TX race and unchecked UART results ------------------------------------ */

/* A master that does not wait: a second frame completes while the first
 * one's answer is coming due. The response delay is 2 ms so a whole read
 * fits before the ping's answer; the read's last byte is swept over every
 * microsecond around that moment. Whatever the timing, every frame on the
 * wire is whole and valid and the UART never refuses an answer (the old
 * loop checked TX, then cancelled the timer, then overwrote the buffer:
 * a timer firing in between sent one answer's head with another's tail). */
static void test_s3_tx_buffer_never_overwritten_while_sending(void **state)
{
    (void)state;
    boot();
    exchange("F9 FF 00 05 03 12 D0 07 0E", 5, NULL); /* 0x12 = 2000 us */
    const uint8_t ping[] = {0xF9, 0xFF, 0x00, 0x02, 0x01, 0xFC};
    uint8_t read[8];
    const uint8_t adr = 0x0A;
    const unsigned rn = kt_command(read, 0x00, 0x02, &adr, 1);
    unsigned answers = 0;
    for (uint32_t off = 0; off < 200u; off++) {
        const uint32_t t0 = kf_world.now;
        kf_send_at(t0, ping, sizeof ping);
        const uint32_t ping_end = kf_world.rx[kf_world.rx_n - 1u].tick;
        const uint32_t read_last = ping_end + 2000u - 100u + off;
        kf_send_at(read_last - (uint32_t)(rn - 1u) * kf_byte_us(), read, rn);
        run_ms(12);
        wire_t w;
        take(&w);
        const unsigned frames = wire_frames_ok(&w);
        if (frames == 0) {
            fail_msg("offset %u: a corrupt frame on the wire (%u bytes)", (unsigned)off, w.n);
        }
        answers += frames;
        assert_int_equal(km_app_tx_refused(), 0);
        assert_int_equal(kf_world.tx_refused, 0);
    }
    assert_true(answers >= 200u);
}

/* The first byte's tick of the first answer since the last look, and the
 * whole answer; 0 bytes if none. */
static unsigned take_answer(wire_t *w, uint32_t *first_tick)
{
    *first_tick = kf_world.tx_n > kf_world.tx_read ? kf_world.tx[kf_world.tx_read].tick : 0u;
    take(w);
    return w->n;
}

/* A read of 0x0A sent to this servo and answered alone: what the reads
 * that follow are measured against. */
typedef struct {
    uint8_t read[8];     /* the read command's bytes */
    unsigned rn;         /* its length */
    uint32_t read_end;   /* its last byte's tick */
    wire_t answer;       /* its answer */
    uint32_t first_tick; /* the answer's first byte's tick */
} alone_read_t;

/* Sends the read, runs 12 ms and takes its answer into *a. */
static void read_answered_alone(alone_read_t *a)
{
    const uint8_t adr = 0x0A;
    a->rn = kt_command(a->read, 0x00, 0x02, &adr, 1);
    kf_send_at(kf_world.now, a->read, a->rn);
    a->read_end = kf_world.rx[kf_world.rx_n - 1u].tick;
    run_ms(12);
    (void)take_answer(&a->answer, &a->first_tick);
}

/* One answer buffer (docs/footprint.md "STM32G031F6"): an answer armed
 * for later (the response delay, 0x12 = 2 ms) stays intact and on time
 * while frames it is not for arrive before it is due: a broadcast read
 * (run, not answered), another servo's ping, and a sync execute to this
 * servo (§3 0x84, no answer: the armed answer is held, then armed again).
 * Same bytes, same delay from the read's end as a read left alone. */
static void test_s3_armed_answer_kept_by_frames_without_answer(void **state)
{
    (void)state;
    boot();
    exchange("F9 FF 00 05 03 12 D0 07 0E", 5, NULL); /* 0x12 = 2000 us */
    alone_read_t alone;
    read_answered_alone(&alone);
    assert_true(alone.answer.n > 0u);
    assert_int_equal(wire_frames_ok(&alone.answer), 1);

    const uint8_t adr = 0x0A;
    uint8_t f[16];
    kf_send_at(kf_world.now, alone.read, alone.rn);
    const uint32_t read_end = kf_world.rx[kf_world.rx_n - 1u].tick;
    kf_send_at(read_end + 200u, f, kt_command(f, KM_ID_BROADCAST, 0x02, &adr, 1));
    kf_send_at(kf_world.rx[kf_world.rx_n - 1u].tick + 100u, f, kt_command(f, 5, 0x01, NULL, 0));
    kf_send_at(kf_world.rx[kf_world.rx_n - 1u].tick + 100u, f, kt_command(f, 0x00, 0x84, NULL, 0));
    assert_true(kf_world.rx[kf_world.rx_n - 1u].tick < read_end + 2000u); /* all before the answer is due */
    run_ms(12);
    wire_t w;
    uint32_t tick;
    assert_int_equal(take_answer(&w, &tick), alone.answer.n);
    assert_memory_equal(w.b, alone.answer.b, alone.answer.n);
    assert_int_equal(tick - read_end, alone.first_tick - alone.read_end);
    assert_int_equal(km_app_tx_refused(), 0);
}

/* A frame for this servo that completes while its previous answer is on
 * the wire waits for that answer's end (the buffer is busy), then is
 * handled and answered: both answers whole, one after the other. */
static void test_s3_frame_during_answer_answered_after_it(void **state)
{
    (void)state;
    boot();
    alone_read_t alone;
    read_answered_alone(&alone);
    const unsigned an = alone.answer.n;
    assert_true(an >= 8u);
    kf_send_at(kf_world.now, alone.read, alone.rn);
    const uint32_t read_end = kf_world.rx[kf_world.rx_n - 1u].tick;
    const uint32_t delay = alone.first_tick - alone.read_end;
    /* A ping whose last byte comes when half the read's answer is sent. */
    const uint32_t half_sent = read_end + delay + (an / 2u) * kf_byte_us();
    uint8_t ping[6];
    const unsigned pn = kt_command(ping, 0x00, 0x01, NULL, 0);
    kf_send_at(half_sent - (pn - 1u) * kf_byte_us(), ping, pn);
    assert_true(kf_world.rx[kf_world.rx_n - 1u].tick > read_end + delay);
    run_ms(12);
    assert_int_equal(kf_world.tx_n - kf_world.tx_read, an + 6u);
    const uint32_t read_answer_last = kf_world.tx[kf_world.tx_read + an - 1u].tick;
    const uint32_t ping_answer_first = kf_world.tx[kf_world.tx_read + an].tick;
    assert_true(ping_answer_first > read_answer_last);
    wire_t w;
    take(&w);
    assert_int_equal(wire_frames_ok(&w), 2);
    assert_memory_equal(w.b, alone.answer.b, an);
    assert_int_equal(w.b[an + 2], 0x00); /* the ping's answer: F9 F5 00 02 status cs */
    assert_int_equal(w.b[an + 3], 0x02);
    assert_int_equal(km_app_tx_refused(), 0);
}

/* A stored baud the board cannot make: the servo opens the bus at 115200
 * (a fresh servo's baud) instead of going deaf, and says so in 0x7F 0x03. */
static void test_s3_unmakeable_baud_falls_back(void **state)
{
    (void)state;
    boot();
    kf_world.unmakeable_baud = 9600u;
    exchange("F9 FF 00 05 03 10 60 00 87", 5, NULL);
    exchange("F9 FF 00 07 03 02 E1 E2 E3 E4 69", 20, NULL);
    assert_int_equal(kf_world.baud, 115200);
    exchange("F9 FF 00 03 02 10 EA", 5, "F9 F5 00 05 02 10 60 00 88"); /* 0x10 still 96 */
    exchange("F9 FF 00 03 7F 03 7A", 5, "F9 F5 00 05 7F 03 80 04 F4"); /* 1152 in force */
}

/* ---- 14 at app level: a long burst, nothing dropped ---------------------------- */

/* 40 pings back to back (240 bytes, more than the 128-byte RX queue) at
 * line rate: every one answered. */
static void test_s3_burst_all_answered(void **state)
{
    (void)state;
    boot();
    for (int i = 0; i < 40; i++) {
        const uint8_t ping[] = {0xF9, 0xFF, 0x00, 0x02, 0x01, 0xFC};
        kf_send_at(kf_world.now, ping, sizeof ping);
    }
    run_ms(60);
    wire_t w;
    take(&w);
    assert_int_equal(wire_frames_ok(&w), 40);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s3_restart_at_once_nothing_after_it_runs),
        cmocka_unit_test(test_s3_restart_after_pending_answer),
        cmocka_unit_test(test_s3_restart_waits_seconds_for_super_id_slot),
        cmocka_unit_test(test_s4_no_stale_bit5_after_id_change),
        cmocka_unit_test(test_s4_bad_checksum_for_our_id_reported_once),
        cmocka_unit_test(test_s4_good_write_after_checksum_error_level1),
        cmocka_unit_test(test_s4_failed_write_survives_a_read_level0),
        cmocka_unit_test(test_s4_multi_id_unsupported_address_is_bit5),
        cmocka_unit_test(test_s7_gap_real_rule),
        cmocka_unit_test(test_s7_gap_delivery_floor),
        cmocka_unit_test(test_wdt_started_before_store_mount),
        cmocka_unit_test(test_ext_reset_cause),
        cmocka_unit_test(test_ext_userdata_source),
        cmocka_unit_test(test_s3_tx_buffer_never_overwritten_while_sending),
        cmocka_unit_test(test_s3_armed_answer_kept_by_frames_without_answer),
        cmocka_unit_test(test_s3_frame_during_answer_answered_after_it),
        cmocka_unit_test(test_s3_unmakeable_baud_falls_back),
        cmocka_unit_test(test_s3_burst_all_answered),
        cmocka_unit_test(test_rx_wakes_main_loop_at_frame_end_only),
    };
    return cmocka_run_group_tests_name("app", tests, NULL, NULL);
}
