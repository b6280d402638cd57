/* SPDX-License-Identifier: Apache-2.0 */
/* Cortex-M0 end-to-end instruction counts (tools/bench/bench-m0): the firmware's
 * real main loop (firmware/app/km_app.c, km_app_init + km_app_poll) over
 * this board's time, flash and system drivers, with the bus UART, motor and
 * sensors replaced by the stand-ins below, so that the benchmark hands a
 * frame's bytes to the app's RX callback itself, exactly when it wants.
 *
 * Per frame: its bytes but the last are handed over and parsed, the loop
 * runs until a control tick has just happened (the next is 1 ms away, so
 * none can land in the measurement), then a region starts, the last byte
 * goes to the RX callback (what the UART interrupt calls, with its tick)
 * and the loop runs. The tool reads the instructions from the region's
 * start to the first entry of km_hal_timer_at (the answer timer armed) and
 * to the first entry of km_hal_idle (the loop has nothing left to do):
 * RX queue, parser, dispatcher, encoder and the app around them. The UART
 * interrupt's own register reads (uart.c) are not in it. Run under
 * -icount shift=0, so that time, and with it the tick, is a function of
 * the instructions executed: the counts are the same on every run.
 *
 * Line rate (issue 8, "back-to-back reception at 1 Mbit/s"): run under
 * -icount shift=6 instead (64 ns of virtual time per instruction: a
 * 15.625 MHz instruction rate, 2.3 % under 16 MHz), the image injects a
 * bus stream at 1 Mbit/s, one byte every 10 us from a TIMER1 interrupt
 * that stands for the UART's (156.25 instructions per byte), into the real
 * main loop with its 1 ms control tick, and counts every frame: delivered
 * by the parser or lost. The image tells the two runs apart by timing its
 * 2,001-instruction validation loop on the 1 MHz hal clock (2 us at
 * shift=0, 128 us at shift=6). */
#include <stdbool.h>
#include <stdint.h>

#include "km_app.h"
#include "km_frame.h"
#include "km_hal_motor.h"
#include "km_hal_sensors.h"
#include "km_hal_time.h"
#include "km_hal_uart.h"
#include "km_parser.h"
#include "nrf51_regs.h"
#include "semihost.h"

/* km_app.c's diagnostics (not in km_app.h, which is not this file's owner). */
const km_parser_stats_t *km_app_parser_stats(void);
uint32_t km_app_rx_dropped(void);

void m0_begin(void);
void m0_end(void);
void m0_region_empty(void);
void m0_region_loop1000(void);

/* ---- stand-ins for the bus UART, motor and sensors ------------------- */

static km_uart_rx_handler_t s_rx;
static void *s_rx_ctx;
static volatile uint32_t s_sent;
static volatile uint32_t s_ticks;

bool km_hal_uart_init(uint32_t baud, km_uart_rx_handler_t handler, void *ctx)
{
    (void)baud;
    s_rx = handler;
    s_rx_ctx = ctx;
    return true;
}

bool km_hal_uart_send(const uint8_t *data, uint16_t len)
{
    (void)data;
    (void)len;
    s_sent++;
    return true;
}

bool km_hal_uart_tx_busy(void)
{
    return false;
}

void km_hal_motor_init(void)
{
}

void km_hal_motor_drive(int16_t pwm)
{
    (void)pwm;
}

void km_hal_motor_free(void)
{
}

void km_hal_motor_brake(void)
{
}

void km_hal_sensors_init(void)
{
}

void km_hal_sensors_read(km_sensors_t *out)
{
    out->position = 0;
    out->current_ma = 120;
    out->voltage_mv = 7400;
    out->temperature_c10 = 250;
    out->faults = 0;
    s_ticks++;
}

/* ---- harness ----------------------------------------------------------- */

static bool s_failed;

static void m0h_say(const char *a, const char *b)
{
    km_semihost_write0(a);
    km_semihost_write0(b);
    km_semihost_write0("\n");
}

/* Runs the loop until a control tick has just happened. */
static void m0h_after_tick(void)
{
    const uint32_t t = s_ticks;
    while (s_ticks == t) {
        km_app_poll();
    }
}

static void m0h_frame(const char *name, uint8_t id, uint8_t cmd, const uint8_t *body, uint8_t n, bool answer,
                      bool changes)
{
    uint8_t f[KM_FRAME_MAX];
    f[0] = KM_HDR0;
    f[1] = KM_HDR1_COMMAND;
    f[2] = id;
    f[3] = (uint8_t)(n + 2u);
    f[4] = cmd;
    for (uint8_t i = 0; i < n; i++) {
        f[5u + i] = body[i];
    }
    f[5u + n] = km_checksum(&f[2], 3u + (uint32_t)n);
    const unsigned len = 6u + n;
    for (unsigned i = 0; i + 1u < len; i++) {
        s_rx(s_rx_ctx, f[i], km_hal_time_now(), false);
        if (i % 32u == 31u) {
            km_app_poll(); /* the RX queue is smaller than a long frame */
        }
    }
    m0h_after_tick(); /* parses them, then the tick */
    const uint32_t sent = s_sent;
    const uint32_t gen = km_servo_params_gen(km_app_servo());
    m0h_say("region e2e_", name);
    const uint32_t now = km_hal_time_now();
    m0_begin();
    s_rx(s_rx_ctx, f[len - 1u], now, false);
    km_app_poll();
    km_app_poll();
    m0_end();
    m0h_after_tick(); /* the answer goes out at its delay */
    m0h_after_tick();
    /* An answer went out, or (writes) a register changed: the frame was
     * handled, not lost. */
    const bool ok = answer ? s_sent != sent : (km_servo_params_gen(km_app_servo()) != gen) == changes;
    km_semihost_write0("check e2e_");
    m0h_say(name, ok ? " ok" : " FAIL");
    if (!ok) {
        s_failed = true;
    }
}

/* ---- line rate: 1 Mbit/s back to back ---------------------------------- */

#define LR_BUF 5000u         /* one lap of the stream, in RAM (50 ms at 1 Mbit/s) */
#define LR_LAPS 2u           /* 100 ms, 100 control ticks per rate */
#define LR_TIMER 0x40009000u /* TIMER1: the stand-in for the UART's byte interrupt */
/* Byte intervals in 16 MHz timer ticks: 160 = 10 us, one 10-bit character
 * at 1 Mbit/s (156.25 instructions at shift=6); the shorter ones give the
 * loop fewer instructions per byte (as a slower clock would) to show where
 * frames start to be lost. */
static const uint32_t s_lr_intervals[] = {160u, 150u, 145u, 140u, 135u, 130u, 120u};
#define LR_IRQ_TIMER1 9u

static uint8_t s_lr[LR_BUF];
static uint32_t s_lr_len;
static uint32_t s_lr_frames;    /* command frames in one lap */
static uint32_t s_lr_responses; /* other servos' answers in one lap */
static volatile uint32_t s_lr_sent;
static uint32_t s_lr_pos;
static uint32_t s_lr_total;
static uint32_t s_lr_rng = 0x2545F491u;

static uint32_t m0h_lr_rand(void) /* xorshift32, as tests/bench/bench_parser.c */
{
    s_lr_rng ^= s_lr_rng << 13;
    s_lr_rng ^= s_lr_rng >> 17;
    s_lr_rng ^= s_lr_rng << 5;
    return s_lr_rng;
}

static void m0h_lr_frame(uint8_t hdr1, uint8_t id, uint8_t cmd, const uint8_t *body, uint8_t n)
{
    uint8_t *f = &s_lr[s_lr_len];
    f[0] = KM_HDR0;
    f[1] = hdr1;
    f[2] = id;
    f[3] = (uint8_t)(n + 2u);
    f[4] = cmd;
    for (uint8_t i = 0; i < n; i++) {
        f[5u + i] = body[i];
    }
    f[5u + n] = km_checksum(&f[2], 3u + (uint32_t)n);
    s_lr_len += 6u + n;
    if (hdr1 == KM_HDR1_COMMAND) {
        s_lr_frames++;
    } else {
        s_lr_responses++;
    }
}

/* The exchanges of the parser's bus mix (tests/bench/m0/gen_mix.py): pings,
 * reads and their answers, moves, 0x83 multi-ID writes, 0x04/0x84 sync
 * writes, torque writes, noise, to IDs 0..11 (0 is this servo: it answers
 * and moves). */
static void m0h_lr_exchange(void)
{
    uint8_t b[64];
    const uint8_t fid = (uint8_t)(m0h_lr_rand() % 12u);
    const uint32_t kind = m0h_lr_rand() % 8u;
    switch (kind) {
    case 0:
        m0h_lr_frame(KM_HDR1_COMMAND, fid, 0x01, b, 0);
        m0h_lr_frame(KM_HDR1_RESPONSE, fid, 0x00, b, 0);
        break;
    case 1:
        b[0] = 0x46;
        m0h_lr_frame(KM_HDR1_COMMAND, fid, 0x02, b, 1);
        b[1] = (uint8_t)m0h_lr_rand();
        b[2] = 0xF9;
        m0h_lr_frame(KM_HDR1_RESPONSE, fid, 0x02, b, 3);
        break;
    case 2:
        b[0] = 0x65; /* a move: +-3276.7 deg at most, in 1 s */
        b[1] = (uint8_t)m0h_lr_rand();
        b[2] = (uint8_t)(m0h_lr_rand() & 0x07u);
        b[3] = 0xE8;
        b[4] = 0x03;
        m0h_lr_frame(KM_HDR1_COMMAND, fid, 0x03, b, 5);
        break;
    case 3: {
        const uint8_t k = (uint8_t)(2u + m0h_lr_rand() % 8u);
        b[0] = 0x65;
        b[1] = 4;
        for (uint8_t i = 0; i < k; i++) {
            b[2u + 5u * i] = i;
            b[3u + 5u * i] = (uint8_t)m0h_lr_rand();
            b[4u + 5u * i] = (uint8_t)(m0h_lr_rand() & 0x07u);
            b[5u + 5u * i] = 0xE8;
            b[6u + 5u * i] = 0x03;
        }
        m0h_lr_frame(KM_HDR1_COMMAND, KM_ID_BROADCAST, 0x83, b, (uint8_t)(2u + 5u * k));
        break;
    }
    case 4:
        for (uint8_t i = 1; i < 4u; i++) {
            b[0] = 0x65;
            b[1] = (uint8_t)m0h_lr_rand();
            b[2] = (uint8_t)(m0h_lr_rand() & 0x07u);
            b[3] = 0xE8;
            b[4] = 0x03;
            m0h_lr_frame(KM_HDR1_COMMAND, i, 0x04, b, 5);
        }
        m0h_lr_frame(KM_HDR1_COMMAND, KM_ID_BROADCAST, 0x84, b, 0);
        break;
    case 5:
        b[0] = 0x64;
        b[1] = 0x02;
        m0h_lr_frame(KM_HDR1_COMMAND, fid, 0x03, b, 2);
        m0h_lr_frame(KM_HDR1_RESPONSE, fid, 0x00, b, 0);
        break;
    case 6:
        b[0] = 0x01;
        m0h_lr_frame(KM_HDR1_COMMAND, fid, 0x02, b, 1);
        b[1] = 0x00;
        b[2] = (uint8_t)m0h_lr_rand();
        m0h_lr_frame(KM_HDR1_RESPONSE, fid, 0x02, b, 3);
        break;
    default:
        for (uint32_t n = 1u + m0h_lr_rand() % 4u; n > 0u; n--) {
            const uint8_t g = (uint8_t)m0h_lr_rand();
            s_lr[s_lr_len++] = g == KM_HDR0 ? 0x00u : g;
        }
        break;
    }
}

static void m0h_lr_generate(void)
{
    /* Whole exchanges only (the longest is < 64 + 4 * 16 bytes), so laps
     * join at an exchange boundary. */
    while (s_lr_len + 200u < LR_BUF) {
        m0h_lr_exchange();
    }
}

/* The UART's byte interrupt, as far as the firmware is concerned: the byte
 * and its tick to the RX callback, one every 10 us. Not harness: its
 * instructions count, as the UART handler's would. */
void TIMER1_IRQHandler(void)
{
    NRF_REG(LR_TIMER, TIMER_EVENTS_COMPARE(0)) = 0u;
    if (s_lr_sent < s_lr_total) {
        const uint8_t byte = s_lr[s_lr_pos];
        s_lr_pos = s_lr_pos + 1u == s_lr_len ? 0u : s_lr_pos + 1u;
        s_lr_sent = s_lr_sent + 1u;
        s_rx(s_rx_ctx, byte, km_hal_time_now(), false);
    }
}

static void m0h_lr_timer_start(uint32_t interval)
{
    NRF_REG(LR_TIMER, TIMER_TASKS_STOP) = 1u;
    NRF_REG(LR_TIMER, TIMER_MODE) = 0u;
    NRF_REG(LR_TIMER, TIMER_BITMODE) = 0u;   /* 16 bit */
    NRF_REG(LR_TIMER, TIMER_PRESCALER) = 0u; /* 16 MHz */
    NRF_REG(LR_TIMER, TIMER_CC(0)) = interval;
    NRF_REG(LR_TIMER, TIMER_SHORTS) = 1u; /* COMPARE0 -> CLEAR: periodic */
    NRF_REG(LR_TIMER, TIMER_EVENTS_COMPARE(0)) = 0u;
    NRF_REG(LR_TIMER, TIMER_INTENSET) = 1u << 16; /* COMPARE0 */
    NRF_REG(LR_TIMER, TIMER_TASKS_CLEAR) = 1u;
    nrf_irq_enable(LR_IRQ_TIMER1);
    NRF_REG(LR_TIMER, TIMER_TASKS_START) = 1u;
}

/* "info linerate_<interval>_<key> <v>" for tools/bench/bench-m0. */
static void m0h_lr_info(uint32_t interval, const char *key, uint32_t v)
{
    km_semihost_write0("info linerate_");
    km_semihost_write_u32(interval);
    km_semihost_write0("_");
    km_semihost_write0(key);
    km_semihost_write0(" ");
    km_semihost_write_u32(v);
    km_semihost_write0("\n");
}

/* One region: LR_LAPS laps of the stream, a byte every `interval` timer
 * ticks, into the running app; then the frames delivered against those
 * sent. */
static void m0h_linerate(uint32_t interval)
{
    s_lr_total = LR_LAPS * s_lr_len;
    s_lr_pos = 0;
    s_lr_sent = 0;
    const km_parser_stats_t *st = km_app_parser_stats();
    const uint32_t frames0 = st->frames_ok;
    const uint32_t responses0 = st->responses_skipped;
    const uint32_t dropped0 = km_app_rx_dropped();
    const uint32_t sent0 = s_sent;
    m0h_after_tick();
    m0h_after_tick();
    const uint32_t ticks0 = s_ticks;
    const uint32_t t0 = km_hal_time_now();
    km_semihost_write0("region linerate_");
    km_semihost_write_u32(interval);
    km_semihost_write0("\n");
    m0_begin();
    m0h_lr_timer_start(interval);
    while (s_lr_sent < s_lr_total) {
        km_app_poll();
    }
    /* The last bytes through the queue (<= 128, 64 per pass) and parser. */
    for (unsigned k = 0; k < 4u; k++) {
        km_app_poll();
    }
    m0_end();
    NRF_REG(LR_TIMER, TIMER_TASKS_STOP) = 1u;
    m0h_lr_info(interval, "bytes", s_lr_total);
    m0h_lr_info(interval, "us", km_hal_time_now() - t0);
    m0h_lr_info(interval, "frames_sent", LR_LAPS * s_lr_frames);
    m0h_lr_info(interval, "frames_got", st->frames_ok - frames0);
    m0h_lr_info(interval, "responses_sent", LR_LAPS * s_lr_responses);
    m0h_lr_info(interval, "responses_skipped", st->responses_skipped - responses0);
    m0h_lr_info(interval, "rx_dropped", km_app_rx_dropped() - dropped0);
    m0h_lr_info(interval, "answers", s_sent - sent0);
    m0h_lr_info(interval, "control_ticks", s_ticks - ticks0);
}

int main(void)
{
    km_app_init();
    /* A frame's last byte comes a control tick after the others: a gap
     * floor far above the real rule, so the parser keeps the frame. */
    km_app_set_bus_floors(1000000u, 0u);
    /* The count validated under -icount too (m0_markers.c), and timed on
     * the 1 MHz hal clock: the instruction rate tells which run this is. */
    m0h_say("region ", "empty");
    m0_region_empty();
    m0h_say("region ", "loop1000_inline");
    const uint32_t v0 = km_hal_time_now();
    m0_region_loop1000();
    const uint32_t loop_us = km_hal_time_now() - v0;
    m0h_after_tick();
    m0h_after_tick();
    if (loop_us >= 50u) { /* shift=6: 2,001 x 64 ns */
        m0h_lr_generate();
        for (unsigned i = 0; i < sizeof s_lr_intervals / sizeof s_lr_intervals[0]; i++) {
            m0h_linerate(s_lr_intervals[i]);
        }
        km_semihost_write0(s_failed ? "bench-m0 FAIL\n" : "bench-m0 done\n");
        km_semihost_exit(s_failed ? 1 : 0);
    }
    uint8_t b[KM_BODY_MAX] = {0};
    m0h_frame("ping", 0, 0x01, b, 0, true, false);
    b[0] = 0x13;
    m0h_frame("read_short_0x13", 0, 0x02, b, 1, true, false);
    b[0] = 0x0A;
    m0h_frame("read_long_0x0A", 0, 0x02, b, 1, true, false);
    b[0] = 0x46;
    m0h_frame("read_super_id_0x46", KM_ID_SUPER, 0x02, b, 1, true, false);
    b[0] = 0x5B;
    b[1] = 0x20;
    b[2] = 0x03;
    m0h_frame("write_0x5B", 0, 0x03, b, 3, false, true);
    b[0] = 0x12;
    b[1] = 0xF4;
    b[2] = 0x01;
    m0h_frame("write_persisted_0x12", 0, 0x03, b, 3, false, true);
    b[0] = 0x12;
    b[1] = 0xC8;
    b[2] = 0x00;
    m0h_frame("write_persisted_0x12_again", 0, 0x03, b, 3, false, true);
    b[0] = 0x65;
    b[1] = 0xC2;
    b[2] = 0x01;
    b[3] = 0xF4;
    b[4] = 0x01;
    m0h_frame("sync_write_0x04", 0, 0x04, b, 5, false, false);
    m0h_frame("sync_execute_0x84", KM_ID_BROADCAST, 0x84, b, 0, false, true);
    for (unsigned entries = 3; entries <= 49; entries += 46) {
        b[0] = 0x65;
        b[1] = 4;
        for (unsigned i = 0; i < entries; i++) {
            uint8_t *e = &b[2 + 5 * i];
            e[0] = (uint8_t)(i + 1u == entries ? 0u : i + 1u);
            e[1] = entries == 3 ? 0x90 : 0x5E; /* +40.0, +35.0 deg: a new target */
            e[2] = 0x01;
            e[3] = 0xF4;
            e[4] = 0x01;
        }
        m0h_frame(entries == 3 ? "multi_write_0x83_3" : "multi_write_0x83_49", KM_ID_BROADCAST, 0x83, b,
                  (uint8_t)(2u + 5u * entries), false, false); /* a move: no register changes */
    }
    b[0] = 0x01;
    m0h_frame("read_status_0x01", 0, 0x02, b, 1, true, false);
    km_semihost_write0(s_failed ? "bench-m0 FAIL\n" : "bench-m0 done\n");
    km_semihost_exit(s_failed ? 1 : 0);
}
