/* SPDX-License-Identifier: Apache-2.0 */
/* The receive interrupt's frame-end tracker (km_rx_track_*, km_parser.h)
 * against the parser it stands in for (docs/protocol.md §2 frames, §7 gap;
 * docs/benchmarks.md "Per byte").
 *
 * The firmware runs the parser only when the tracker asks (or on a control
 * tick), then re-aligns the tracker with the parser. Modelled here: a
 * reference parser fed every byte at once; a second parser fed the queued
 * bytes only when the tracker asks or a random "tick" comes, the tracker
 * re-aligned after each drain. Checked on seeded streams of good and
 * corrupted frames, other servos' responses, truncated frames, bad headers,
 * noise, gaps and lost bytes:
 *  - no frame late: on every byte on which the reference hands a frame out
 *    the tracker asked, so the firmware's parser hands it out on that byte;
 *  - both parsers hand out the same frames;
 *  - no pass for nothing: on a stream of whole frames with no gap, the
 *    tracker asks on each frame's last byte and otherwise only every 64
 *    bytes of a long frame. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "parser_stream.h"

#define GAP 8u
#define STREAM 100000u

static ps_stream_t s_ps;

/* The next number of the stream's generator, for the test's own draws. */
static uint32_t rnd(void)
{
    return ps_rnd(&s_ps);
}

/* Runs one stream through both; returns the tracker's wake-ups. */
static size_t run_stream(uint32_t seed, bool clean, size_t *frames_out)
{
    static km_parser_t ref;
    static km_parser_t fw;
    km_rx_track_t track = {0};
    ps_make(&s_ps, seed, STREAM, GAP, clean);
    km_parser_init(&ref, GAP);
    km_parser_init(&fw, GAP);
    track.gap_ticks = GAP;
    track.last_tick = s_ps.ticks[0];
    size_t queued = 0; /* bytes received, not yet fed to fw */
    size_t wakes = 0;
    size_t frames_ref = 0;
    size_t frames_fw = 0;
    km_frame_t f_ref;
    km_frame_t f_fw;
    for (size_t i = 0; i < s_ps.len; i++) {
        if (s_ps.lost[i]) {
            km_parser_overrun(&ref);
        }
        const unsigned ev_ref = km_parser_feed(&ref, s_ps.bytes[i], s_ps.ticks[i], &f_ref);
        const bool wake = km_rx_track_byte(&track, s_ps.bytes[i], s_ps.ticks[i], s_ps.lost[i] != 0u);
        wakes += wake;
        if (clean && s_ps.last[i]) {
            assert_true(wake);
        } else if (clean) { /* no pass for a byte inside a frame but every 64 of a long one */
            assert_true(!wake || (track.state == KM_TRACK_COUNT && (track.left & 63u) == 0u));
        }
        if (ev_ref & KM_PARSE_FRAME) {
            frames_ref++;
            assert_true(wake); /* a frame the firmware would hand out late */
        }
        if (wake || rnd() % 50u == 0u) { /* a pass of the main loop */
            for (size_t k = queued; k <= i; k++) {
                if (s_ps.lost[k]) {
                    km_parser_overrun(&fw);
                }
                const unsigned ev = km_parser_feed(&fw, s_ps.bytes[k], s_ps.ticks[k], &f_fw);
                if (ev & KM_PARSE_FRAME) {
                    frames_fw++;
                    assert_int_equal(k, i); /* only on the byte the reference did */
                    assert_true(ev_ref & KM_PARSE_FRAME);
                    assert_int_equal(f_fw.id, f_ref.id);
                    assert_int_equal(f_fw.cmd, f_ref.cmd);
                    assert_int_equal(f_fw.body_len, f_ref.body_len);
                    assert_memory_equal(f_fw.body, f_ref.body, f_fw.body_len);
                    assert_int_equal(f_fw.end_tick, f_ref.end_tick);
                }
            }
            queued = i + 1u;
            km_rx_track_sync(&track, &fw);
        }
    }
    assert_int_equal(frames_fw, frames_ref);
    *frames_out = frames_ref;
    return wakes;
}

static void test_tracker_never_late_on_rough_streams(void **state)
{
    (void)state;
    for (uint32_t seed = 1; seed <= 6; seed++) {
        size_t frames = 0;
        const size_t wakes = run_stream(0x9E3779B9u * seed, false, &frames);
        assert_true(frames > 1000u);
        assert_true(wakes < s_ps.len / 2u); /* a rough stream still skips most bytes */
    }
}

static void test_tracker_wakes_once_per_frame_on_clean_streams(void **state)
{
    (void)state;
    for (uint32_t seed = 1; seed <= 3; seed++) {
        size_t frames = 0;
        const size_t wakes = run_stream(0x7F4A7C15u * seed, true, &frames);
        assert_true(frames > 1000u);
        assert_true(wakes >= frames); /* responses wake too: the parser skips them */
    }
}

/* A byte that never completes a frame (a bad length) puts the tracker out
 * of step: it asks on every byte until it is re-aligned (§2 lengths 2..252). */
static void test_tracker_bad_length_asks_until_sync(void **state)
{
    (void)state;
    km_parser_t p;
    km_parser_init(&p, GAP);
    km_rx_track_t t = {.gap_ticks = GAP};
    const uint8_t bad[] = {0xF9, 0xFF, 0x01, 0x01};
    for (size_t i = 0; i < 3u; i++) {
        assert_false(km_rx_track_byte(&t, bad[i], 1u, false));
    }
    assert_true(km_rx_track_byte(&t, bad[3], 1u, false));
    assert_true(km_rx_track_byte(&t, 0x00, 1u, false));
    km_rx_track_sync(&t, &p); /* an empty parser: hunting again */
    assert_false(km_rx_track_byte(&t, 0x00, 1u, false));
}

/* 64 bytes of a long frame wake the main loop (the queue holds 128), and a
 * gap inside a frame hands the byte to the parser (§7). */
static void test_tracker_long_frame_and_gap(void **state)
{
    (void)state;
    km_rx_track_t t = {.gap_ticks = GAP};
    const uint8_t head[] = {0xF9, 0xFF, 0xFE, 200};
    for (size_t i = 0; i < 4u; i++) {
        assert_false(km_rx_track_byte(&t, head[i], 1u, false));
    }
    unsigned woke = 0;
    for (unsigned i = 0; i < 199u; i++) {
        woke += km_rx_track_byte(&t, 0x00, 1u, false);
    }
    assert_int_equal(woke, 3); /* 192, 128 and 64 left */
    assert_true(km_rx_track_byte(&t, 0x00, 1u + GAP + 1u, false));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tracker_never_late_on_rough_streams),
        cmocka_unit_test(test_tracker_wakes_once_per_frame_on_clean_streams),
        cmocka_unit_test(test_tracker_bad_length_asks_until_sync),
        cmocka_unit_test(test_tracker_long_frame_and_gap),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
