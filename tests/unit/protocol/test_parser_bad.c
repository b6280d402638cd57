/* SPDX-License-Identifier: Apache-2.0 */
/* Frame parser tests, part 2: the bad-input catalog. Each case states its
 * defined outcome (no frame, which counter) and checks that a good frame
 * right after it still arrives (docs/protocol.md §2 frames, §4 checksum
 * decision, §7 gap). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "parser_rig.h"

#define GAP 10u

static const uint8_t s_ping1[] = {0xF9, 0xFF, 0x01, 0x02, 0x01, 0xFB};
static const uint8_t s_write65[] = {0xF9, 0xFF, 0x01, 0x07, 0x03, 0x65, 0x84, 0x03, 0xE8, 0x03, 0x1D};

static void assert_ping1(const km_frame_t *f)
{
    assert_int_equal(f->id, 1);
    assert_int_equal(f->cmd, 0x01);
    assert_int_equal(f->body_len, 0);
}

/* Feeds `bad`, then the ping without a gap: exactly the ping comes out. */
static rig_t *bad_then_ping(const uint8_t *bad, size_t n)
{
    static rig_t r;
    rig_init(&r, GAP, 100u);
    rig_feed(&r, bad, n, 1u);
    assert_int_equal(r.n, 0);
    rig_feed(&r, s_ping1, sizeof s_ping1, 1u);
    assert_int_equal(r.n, 1);
    assert_ping1(&r.frames[0]);
    return &r;
}

/* §2: bytes that are not an F9 FF header are hunted through, uncounted. */
static void test_s2_wrong_header_bytes(void **state)
{
    (void)state;
    static const uint8_t cases[][4] = {
        {0xFF, 0xF9, 0x00, 0x00},                           /* swapped header */
        {0xF9, 0x00, 0x01, 0x02},                           /* F9 then not FF/F5 */
        {0xF9, 0xFE, 0x01, 0x02}, {0xF9, 0xF9, 0xF9, 0xF9}, /* repeated F9: each fails against the next */
        {0xFF, 0xFF, 0xFF, 0xFF},
    };
    for (unsigned i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        rig_t *r = bad_then_ping(cases[i], 4);
        assert_int_equal(r->p.stats.framing_errors, 0);
        assert_int_equal(r->p.stats.checksum_errors, 0);
    }
}

/* §2: length outside 2..252 is a framing error; the candidate's F9 is
 * dropped and the ping after it is found. */
static void test_s2_length_out_of_range(void **state)
{
    (void)state;
    static const uint8_t bad_len[] = {0, 1, 253, 254, 255};
    for (unsigned i = 0; i < sizeof bad_len; i++) {
        const uint8_t bad[] = {0xF9, 0xFF, 0x01, bad_len[i], 0x01};
        rig_t *r = bad_then_ping(bad, sizeof bad);
        assert_int_equal(r->p.stats.framing_errors, 1);
        assert_int_equal(r->p.stats.frames_ok, 1);
    }
    /* Lengths 2 and 252 are the edges that pass (see test_parser.c). */
}

/* §1: IDs 251, 252 and 255 fail the header even with a right checksum. */
static void test_s1_unaddressable_ids_fail_header(void **state)
{
    (void)state;
    static const uint8_t ids[] = {251, 252, 255};
    for (unsigned i = 0; i < sizeof ids; i++) {
        uint8_t bad[8];
        size_t n = rig_command(bad, ids[i], 0x01, NULL, 0);
        rig_t *r = bad_then_ping(bad, n);
        assert_int_equal(r->p.stats.framing_errors, 1);
        assert_int_equal(r->p.stats.checksum_errors, 0);
    }
}

/* §2, §4 Decision: a bad checksum gives no frame, raises the event and
 * records the frame's ID once, for our ID or any other. */
static void test_s4_bad_checksum_records_id(void **state)
{
    (void)state;
    static const uint8_t ids[] = {1, 7, 0, 250, 253, 254};
    for (unsigned i = 0; i < sizeof ids; i++) {
        uint8_t bad[8];
        size_t n = rig_command(bad, ids[i], 0x01, NULL, 0);
        bad[n - 1u] ^= 0x01u;
        rig_t *r = bad_then_ping(bad, n);
        assert_int_equal(r->checksum_events, 1);
        assert_int_equal(r->p.stats.checksum_errors, 1);
        assert_int_equal(r->p.stats.framing_errors, 0);
        assert_true(km_parser_take_checksum_error(&r->p, ids[i]));
        assert_false(km_parser_take_checksum_error(&r->p, ids[i])); /* cleared */
    }
}

/* §4 Decision (bit 5 only for our ID), issue 13 item 3: taking the record
 * forgets every ID's, so a bad frame for ID 5 seen while we are ID 0 is not
 * claimed after we become ID 5. */
static void test_s4_take_forgets_other_ids(void **state)
{
    (void)state;
    uint8_t bad[8];
    size_t n = rig_command(bad, 5, 0x01, NULL, 0);
    bad[n - 1u] ^= 0x01u;
    rig_t *r = bad_then_ping(bad, n);
    assert_int_equal(r->checksum_events, 1);
    assert_false(km_parser_take_checksum_error(&r->p, 0)); /* asked as ID 0 */
    assert_false(km_parser_take_checksum_error(&r->p, 5)); /* ID 5's record is gone too */
}

/* §7: a truncated frame then silence: a poll at exactly the gap keeps it, a
 * poll one tick later drops it (one timeout); the next frame arrives. */
static void test_s7_truncated_then_silence(void **state)
{
    (void)state;
    rig_t r;
    rig_init(&r, GAP, 100u);
    uint32_t last = rig_feed(&r, s_write65, 7, 1u);
    rig_poll(&r, last + GAP);
    assert_int_equal(r.p.stats.timeouts, 0);
    assert_int_equal(r.p.fill, 7);
    rig_poll(&r, last + GAP + 1u);
    assert_int_equal(r.p.stats.timeouts, 1);
    assert_int_equal(r.p.fill, 0);
    rig_poll(&r, last + GAP + 50u); /* idempotent */
    assert_int_equal(r.p.stats.timeouts, 1);
    r.tick = last + 1000u;
    rig_feed(&r, s_write65, sizeof s_write65, 1u);
    assert_int_equal(r.n, 1);
    assert_int_equal(r.frames[0].cmd, 0x03);
}

/* §7: the gap also drops a frame when the next byte, not a poll, notices. */
static void test_s7_truncated_then_late_frame(void **state)
{
    (void)state;
    rig_t r;
    rig_init(&r, GAP, 100u);
    uint32_t last = rig_feed(&r, s_write65, 5, 1u);
    r.tick = last + GAP + 1u;
    rig_feed(&r, s_ping1, sizeof s_ping1, 1u);
    assert_int_equal(r.n, 1);
    assert_ping1(&r.frames[0]);
    assert_int_equal(r.p.stats.timeouts, 1);
    assert_int_equal(r.p.stats.checksum_errors, 0);
}

/* §2: a truncated frame followed at once by a good frame: the truncated
 * candidate swallows the good one's bytes until its own length is reached,
 * fails its checksum (indistinguishable on the wire from a bad checksum),
 * and the good frame is found in the bytes already seen. */
static void test_s2_truncated_then_good_without_gap(void **state)
{
    (void)state;
    rig_t r;
    rig_init(&r, GAP, 100u);
    rig_feed(&r, s_write65, 6, 1u); /* length 7: needs 11 bytes */
    uint32_t last = rig_feed(&r, s_ping1, sizeof s_ping1, 1u);
    assert_int_equal(r.n, 1);
    assert_ping1(&r.frames[0]);
    assert_int_equal(r.frames[0].end_tick, last);
    assert_int_equal(r.p.stats.checksum_errors, 1);
    assert_int_equal(r.checksum_events, 1);
    assert_int_equal(r.p.stats.timeouts, 0);
    assert_int_equal(r.p.fill, 0);
}

/* §2: the brief's example F9 FF 01 F9 FF 01 02 01 FB: the first candidate
 * has length F9 (valid, 253 bytes), so the ping inside it comes out when
 * that candidate fails: here by the gap, found by a poll. */
static void test_s2_nested_candidate_released_by_gap(void **state)
{
    (void)state;
    static const uint8_t stream[] = {0xF9, 0xFF, 0x01, 0xF9, 0xFF, 0x01, 0x02, 0x01, 0xFB};
    rig_t r;
    rig_init(&r, GAP, 100u);
    uint32_t last = rig_feed(&r, stream, sizeof stream, 1u);
    assert_int_equal(r.n, 0);
    rig_poll(&r, last + GAP + 1u);
    assert_int_equal(r.n, 1);
    assert_ping1(&r.frames[0]);
    assert_int_equal(r.frames[0].end_tick, last); /* the ping's last byte */
    assert_int_equal(r.p.stats.timeouts, 1);
}

/* §2: the same candidate fails by its checksum when its 253 bytes arrive;
 * the ping hidden in its length is then delivered. */
static void test_s2_good_frame_hidden_in_bad_candidate_length(void **state)
{
    (void)state;
    static uint8_t stream[253];
    static const uint8_t head[] = {0xF9, 0xFF, 0x01, 0xF9, 0xFF, 0x01, 0x02, 0x01, 0xFB};
    memcpy(stream, head, sizeof head);
    for (unsigned i = sizeof head; i < sizeof stream; i++) {
        stream[i] = 0x00; /* filler; makes the checksum wrong */
    }
    rig_t r;
    rig_init(&r, GAP, 100u);
    rig_feed(&r, stream, sizeof stream - 1u, 1u);
    assert_int_equal(r.n, 0);
    rig_feed(&r, &stream[sizeof stream - 1u], 1u, 1u);
    assert_int_equal(r.n, 1);
    assert_ping1(&r.frames[0]);
    assert_int_equal(r.p.stats.checksum_errors, 1);
    /* The call stopped at the ping; the filler after it is judged (and
     * dropped) by the next call. */
    assert_true(r.p.pending);
    rig_poll(&r, r.p.last_tick);
    assert_int_equal(r.n, 1);
    assert_int_equal(r.p.fill, 0);
}

/* §2: two frames hidden in one failed candidate: one call hands out one
 * frame, the next feed or poll hands out the other, in order. */
static void test_s2_two_hidden_frames_one_per_call(void **state)
{
    (void)state;
    static const uint8_t stream[] = {
        0xF9, 0xFF, 0x01, 0x0E,             /* candidate: needs 18 bytes */
        0xF9, 0xFF, 0x01, 0x02, 0x01, 0xFB, /* ping 1 */
        0xF9, 0xFF, 0x02, 0x02, 0x01, 0xFA, /* ping 2 */
        0x00, 0x00,                         /* candidate's bad checksum */
    };
    for (unsigned by_poll = 0; by_poll < 2; by_poll++) {
        rig_t r;
        rig_init(&r, GAP, 100u);
        uint32_t last = rig_feed(&r, stream, sizeof stream, 1u);
        assert_int_equal(r.n, 1);
        assert_int_equal(r.frames[0].id, 1);
        assert_true(r.p.pending);
        if (by_poll) {
            rig_poll(&r, last); /* within the gap: still hands it out */
        } else {
            rig_feed(&r, s_ping1, sizeof s_ping1, 1u);
        }
        assert_int_equal(r.frames[1].id, 2);
        assert_int_equal(r.n, by_poll ? 2u : 3u);
        assert_false(r.p.pending);
        assert_int_equal(r.p.stats.frames_ok, r.n);
    }
}

/* §7: while frames found by a resync wait to be handed out, a second cut
 * (here two overruns) must not let a frame span the first cut: ping 9
 * starts before the first overrun and ends between the two. The waiting
 * frames still come out, in order. */
static void test_s7_no_frame_across_two_cuts_while_pending(void **state)
{
    (void)state;
    uint8_t stream[80] = {0xF9, 0xFF, 0x01, 0x32}; /* candidate: needs 54 bytes */
    size_t n = 4;
    for (uint8_t id = 1; id <= 8; id++) {
        n += rig_command(&stream[n], id, 0x01, NULL, 0); /* eight hidden pings */
    }
    stream[n++] = 0x00;
    stream[n++] = 0x00; /* the candidate's bad checksum */
    assert_int_equal(n, 54);
    uint8_t ping9[8];
    rig_command(ping9, 9, 0x01, NULL, 0);
    rig_t r;
    rig_init(&r, GAP, 0u);
    rig_feed(&r, stream, n, 1u); /* hands out ping 1 */
    rig_feed(&r, ping9, 5, 1u);  /* pings 2..6; ping 9 lacks its checksum */
    assert_int_equal(r.n, 6);
    km_parser_overrun(&r.p);
    rig_feed(&r, &ping9[5], 1, 1u); /* ping 7 */
    km_parser_overrun(&r.p);
    rig_poll(&r, r.tick); /* ping 8 */
    rig_poll(&r, r.tick + GAP + 1u);
    assert_int_equal(r.n, 8);
    for (unsigned i = 0; i < 8; i++) {
        assert_int_equal(r.frames[i].id, i + 1u); /* never ID 9 */
    }
    assert_int_equal(r.p.fill, 0);
}

/* §2: other servos' responses are skipped whole, even when their body holds
 * a valid command frame. */
static void test_s2_response_with_embedded_command_skipped(void **state)
{
    (void)state;
    /* F9 F5 02 len 02 [F9 FF 01 02 01 FB] cs: a read answer carrying a ping */
    uint8_t resp[16] = {0xF9, 0xF5, 0x02, 0x08, 0x02, 0xF9, 0xFF, 0x01, 0x02, 0x01, 0xFB};
    resp[11] = km_checksum(&resp[2], 9);
    rig_t *r = bad_then_ping(resp, 12);
    assert_int_equal(r->p.stats.responses_skipped, 1);
    assert_int_equal(r->p.stats.frames_ok, 1);
    assert_int_equal(r->p.stats.checksum_errors, 0);
}

/* §2: a response with a bad checksum resyncs inside itself (its embedded
 * ping is then a frame); no checksum event, it was not a command. */
static void test_s2_bad_response_resyncs_inside(void **state)
{
    (void)state;
    uint8_t resp[16] = {0xF9, 0xF5, 0x02, 0x08, 0x02, 0xF9, 0xFF, 0x01, 0x02, 0x01, 0xFB};
    resp[11] = (uint8_t)(km_checksum(&resp[2], 9) ^ 0x10u);
    rig_t r;
    rig_init(&r, GAP, 0u);
    rig_feed(&r, resp, 12, 1u);
    assert_int_equal(r.n, 1);
    assert_ping1(&r.frames[0]);
    assert_int_equal(r.p.stats.checksum_errors, 1);
    assert_int_equal(r.checksum_events, 0);
    assert_int_equal(r.p.stats.responses_skipped, 0);
    /* Bad response length: framing error, the rest is hunted. */
    static const uint8_t bad_len[] = {0xF9, 0xF5, 0x01, 0x00};
    rig_t *r2 = bad_then_ping(bad_len, sizeof bad_len);
    assert_int_equal(r2->p.stats.framing_errors, 1);
    /* Response IDs are servo IDs: 253 is a framing error. */
    static const uint8_t bad_id[] = {0xF9, 0xF5, 0xFD, 0x02, 0x00, 0xFF};
    r2 = bad_then_ping(bad_id, sizeof bad_id);
    assert_int_equal(r2->p.stats.framing_errors, 1);
    assert_int_equal(r2->p.stats.responses_skipped, 0);
}

/* §2: garbage (no F9) before, between and after frames changes nothing. */
static void test_s2_garbage_around_frames(void **state)
{
    (void)state;
    static const uint8_t junk[] = {0x00, 0xFF, 0xF5, 0x13, 0xFE, 0x01};
    rig_t r;
    rig_init(&r, GAP, 0u);
    for (unsigned i = 0; i < 4; i++) {
        rig_feed(&r, junk, sizeof junk, 1u);
        rig_feed(&r, s_write65, sizeof s_write65, 1u);
    }
    rig_feed(&r, junk, sizeof junk, 1u);
    assert_int_equal(r.n, 4);
    assert_int_equal(r.p.stats.framing_errors + r.p.stats.checksum_errors + r.p.stats.timeouts, 0);
    assert_int_equal(r.p.fill, 0);
    /* A stray F9 right before a frame: F9 F9 fails, the next F9 wins. */
    static const uint8_t stray[] = {0xF9};
    rig_t *r2 = bad_then_ping(stray, 1);
    assert_int_equal(r2->p.stats.framing_errors, 0);
}

/* §7: an overrun drops the partial frame (counted as an overrun, not a
 * timeout); the rest of the lost frame is hunted through; the next arrives. */
static void test_s7_overrun_drops_partial(void **state)
{
    (void)state;
    rig_t r;
    rig_init(&r, GAP, 0u);
    rig_feed(&r, s_write65, 4, 1u);
    km_parser_overrun(&r.p);
    rig_feed(&r, &s_write65[6], sizeof s_write65 - 6u, 1u);
    assert_int_equal(r.n, 0);
    rig_feed(&r, s_write65, sizeof s_write65, 1u);
    assert_int_equal(r.n, 1);
    assert_int_equal(r.p.stats.overruns, 1);
    assert_int_equal(r.p.stats.timeouts, 0);
    /* A frame complete before the overrun is still handed out. */
    static const uint8_t nested[] = {0xF9, 0xFF, 0x01, 0xF9, 0xFF, 0x01, 0x02, 0x01, 0xFB};
    rig_init(&r, GAP, 0u);
    rig_feed(&r, nested, sizeof nested, 1u);
    km_parser_overrun(&r.p);
    rig_feed(&r, s_write65, sizeof s_write65, 1u);
    assert_int_equal(r.n, 2);
    assert_ping1(&r.frames[0]);
    assert_int_equal(r.frames[1].cmd, 0x03);
}

/* §7: ticks wrap around uint32_t: inside the gap across the wrap is kept,
 * a silence across the wrap still drops. */
static void test_s7_tick_wraparound(void **state)
{
    (void)state;
    rig_t r;
    rig_init(&r, GAP, UINT32_MAX - 4u);
    uint32_t last = rig_feed(&r, s_write65, sizeof s_write65, 1u);
    assert_int_equal(r.n, 1);
    assert_int_equal(r.frames[0].end_tick, last);
    assert_true(last < 100u); /* really wrapped */

    rig_init(&r, GAP, UINT32_MAX - 4u);
    last = rig_feed(&r, s_write65, 3, 1u); /* last = UINT32_MAX - 2 */
    rig_poll(&r, last + GAP);              /* wraps, within the gap */
    assert_int_equal(r.p.stats.timeouts, 0);
    rig_poll(&r, last + GAP + 1u);
    assert_int_equal(r.p.stats.timeouts, 1);
}

/* Counters saturate instead of wrapping. */
static void test_s2_counters_saturate(void **state)
{
    (void)state;
    rig_t r;
    rig_init(&r, GAP, 0u);
    r.p.stats.frames_ok = UINT32_MAX;
    r.p.stats.overruns = UINT32_MAX;
    rig_feed(&r, s_ping1, sizeof s_ping1, 1u);
    km_parser_overrun(&r.p);
    assert_int_equal(r.n, 1);
    assert_true(r.p.stats.frames_ok == UINT32_MAX);
    assert_true(r.p.stats.overruns == UINT32_MAX);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s2_wrong_header_bytes),
        cmocka_unit_test(test_s2_length_out_of_range),
        cmocka_unit_test(test_s1_unaddressable_ids_fail_header),
        cmocka_unit_test(test_s4_bad_checksum_records_id),
        cmocka_unit_test(test_s4_take_forgets_other_ids),
        cmocka_unit_test(test_s7_truncated_then_silence),
        cmocka_unit_test(test_s7_truncated_then_late_frame),
        cmocka_unit_test(test_s2_truncated_then_good_without_gap),
        cmocka_unit_test(test_s2_nested_candidate_released_by_gap),
        cmocka_unit_test(test_s2_good_frame_hidden_in_bad_candidate_length),
        cmocka_unit_test(test_s2_two_hidden_frames_one_per_call),
        cmocka_unit_test(test_s7_no_frame_across_two_cuts_while_pending),
        cmocka_unit_test(test_s2_response_with_embedded_command_skipped),
        cmocka_unit_test(test_s2_bad_response_resyncs_inside),
        cmocka_unit_test(test_s2_garbage_around_frames),
        cmocka_unit_test(test_s7_overrun_drops_partial),
        cmocka_unit_test(test_s7_tick_wraparound),
        cmocka_unit_test(test_s2_counters_saturate),
    };
    return cmocka_run_group_tests_name("parser_bad", tests, NULL, NULL);
}
