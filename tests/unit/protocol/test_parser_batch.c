/* SPDX-License-Identifier: Apache-2.0 */
/* Frame parser tests, part 4: the batch entry (km_parser_feed_bytes) is the
 * byte entry (km_parser_feed) run byte by byte, differentially.
 *
 * Two parsers get the same seeded streams: good and corrupted command
 * frames, other servos' responses (docs/protocol.md §2), truncated frames, noise
 * with F9 and F9 FF in it, ticks that stand still, step, or jump past the
 * gap (§7), overruns and polls. One parser is fed byte by byte, the other
 * in runs of random length. After every batch call the byte-fed parser has
 * been fed the bytes the call consumed, and then: the events OR-ed over
 * those bytes equal the call's, a frame came out on the consumed run's
 * last byte and nowhere before, its fields are equal (the view's body
 * against the copy), checksum-error records answer alike, and the two
 * parsers' states are equal (check_same_state). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "parser_rig.h"

#define GAP 8u
#define STREAM 200000u

static uint32_t s_rng;

static uint32_t rnd(void) /* xorshift32 */
{
    s_rng ^= s_rng << 13;
    s_rng ^= s_rng >> 17;
    s_rng ^= s_rng << 5;
    return s_rng;
}

static uint8_t s_bytes[STREAM + 512u];
static uint32_t s_ticks[STREAM + 512u];
static uint8_t s_overrun[STREAM + 512u]; /* 1: an overrun before this byte */
static size_t s_len;

static void put(uint8_t b)
{
    s_bytes[s_len++] = b;
}

static void put_frame(uint8_t hdr1, uint8_t id, size_t body_len, bool corrupt, bool truncate)
{
    uint8_t f[KM_FRAME_MAX];
    uint8_t body[KM_BODY_MAX];
    for (size_t i = 0; i < body_len; i++) {
        /* Now and then a header inside a body: a candidate inside a frame. */
        body[i] = (rnd() % 16u == 0u) ? (uint8_t)((i & 1u) ? 0xFFu : 0xF9u) : (uint8_t)rnd();
    }
    size_t n = rig_command(f, id, (uint8_t)rnd(), body, body_len);
    f[1] = hdr1;
    if (corrupt) {
        f[n - 1u] = (uint8_t)(f[n - 1u] ^ (1u + rnd() % 255u));
    }
    if (truncate) {
        n = 1u + rnd() % (n - 1u);
    }
    for (size_t i = 0; i < n; i++) {
        put(f[i]);
    }
}

static uint8_t any_id(void)
{
    const uint32_t r = rnd() % 16u;
    return r == 0u ? 0xFDu : r == 1u ? 0xFEu : r == 2u ? (uint8_t)rnd() : (uint8_t)(r - 3u);
}

/* One stream: pieces of every kind, then ticks and overruns over it. */
static void make_stream(void)
{
    s_len = 0;
    while (s_len < STREAM) {
        const uint32_t kind = rnd() % 10u;
        const size_t body_len = (rnd() % 8u == 0u) ? rnd() % (KM_BODY_MAX + 1u) : rnd() % 12u;
        switch (kind) {
        case 0:
        case 1:
        case 2:
            put_frame(0xFF, any_id(), body_len, false, false);
            break;
        case 3:
            put_frame(0xF5, (uint8_t)(rnd() % 12u), body_len, false, false);
            break;
        case 4:
            put_frame(0xFF, any_id(), body_len, true, false);
            break;
        case 5:
            put_frame(0xF5, (uint8_t)(rnd() % 12u), body_len, true, false);
            break;
        case 6:
            put_frame(rnd() % 2u ? 0xFFu : 0xF5u, any_id(), body_len, false, true);
            break;
        case 7: { /* a bad length or ID after a real header */
            put(0xF9);
            put(0xFF);
            put(rnd() % 2u ? (uint8_t)(251u + rnd() % 2u) : 1u);
            put((uint8_t)(rnd() % 2u ? 0u : 253u + rnd() % 3u));
            break;
        }
        default: /* noise, F9 and F9 FF in it */
            for (uint32_t i = 1u + rnd() % 6u; i > 0u; i--) {
                const uint32_t r = rnd() % 8u;
                put(r == 0u ? 0xF9u : r == 1u ? 0xFFu : (uint8_t)rnd());
            }
            break;
        }
    }
    uint32_t t = rnd(); /* anywhere, so the 32-bit wrap is crossed at times */
    for (size_t i = 0; i < s_len; i++) {
        const uint32_t r = rnd() % 64u;
        t += r == 0u ? GAP + 1u + rnd() % 20u : r == 1u ? GAP : r < 8u ? 0u : 1u;
        s_ticks[i] = t;
        s_overrun[i] = rnd() % 997u == 0u;
    }
}

static void check_same_frame(const km_frame_t *copy, const km_frame_view_t *view)
{
    assert_int_equal(copy->id, view->id);
    assert_int_equal(copy->cmd, view->cmd);
    assert_int_equal(copy->body_len, view->body_len);
    assert_memory_equal(copy->body, view->body, copy->body_len);
    assert_int_equal(copy->end_tick, view->end_tick);
}

/* Equal as far as anything after can tell: the bytes waiting (where they
 * sit in the ring may differ: a frame judged in the caller's bytes never
 * enters it), their prefix sums relative to each other (only differences
 * of two are ever used), and every other field. */
static void check_same_state(const km_parser_t *a, const km_parser_t *b)
{
    assert_int_equal(a->fill, b->fill);
    assert_int_equal(a->need, b->need);
    assert_int_equal(a->stale, b->stale);
    assert_int_equal(a->pending, b->pending);
    assert_int_equal(a->stale_by_gap, b->stale_by_gap);
    assert_int_equal(a->last_tick, b->last_tick);
    assert_int_equal(a->stale_tick, b->stale_tick);
    assert_int_equal(a->gap_ticks, b->gap_ticks);
    assert_int_equal(a->acc, b->acc);
    assert_memory_equal(&a->stats, &b->stats, sizeof a->stats);
    assert_memory_equal(a->bad_ids, b->bad_ids, sizeof a->bad_ids);
    for (unsigned k = 0; k < a->fill; k++) {
        const uint8_t ia = (uint8_t)(a->head + k);
        const uint8_t ib = (uint8_t)(b->head + k);
        assert_int_equal(a->window[ia], b->window[ib]);
        assert_int_equal(a->psum[ia], b->psum[ib]);
    }
}

static void run_stream(uint32_t seed, uint32_t max_run)
{
    static km_parser_t by_byte;
    static km_parser_t by_run;
    static km_parser_out_t out;
    s_rng = seed;
    make_stream();
    km_parser_init(&by_byte, GAP);
    km_parser_init(&by_run, GAP);
    unsigned frames = 0;
    size_t i = 0;
    while (i < s_len) {
        if (s_overrun[i]) {
            km_parser_overrun(&by_byte);
            km_parser_overrun(&by_run);
        }
        /* A run stops before the next overrun, as the RX queue's does. */
        uint32_t n = 1u + rnd() % max_run;
        if (n > s_len - i) {
            n = (uint32_t)(s_len - i);
        }
        for (uint32_t k = 1; k < n; k++) {
            if (s_overrun[i + k]) {
                n = k;
                break;
            }
        }
        uint32_t used = 0;
        const unsigned ev = km_parser_feed_bytes(&by_run, &s_bytes[i], &s_ticks[i], n, &used, &out);
        assert_true(used >= 1u && used <= n);
        unsigned ev_bytes = 0;
        km_frame_t copy;
        for (uint32_t k = 0; k < used; k++) {
            const unsigned e = km_parser_feed(&by_byte, s_bytes[i + k], s_ticks[i + k], &copy);
            ev_bytes |= e;
            /* A frame ends the run, and only the last byte's feed hands one. */
            assert_true(!(e & KM_PARSE_FRAME) || k + 1u == used);
        }
        assert_int_equal(ev, ev_bytes);
        assert_true((ev & KM_PARSE_FRAME) || used == n);
        if (ev & KM_PARSE_FRAME) {
            check_same_frame(&copy, &out.frame);
            frames++;
        }
        i += used;
        if (ev & KM_PARSE_CHECKSUM_ERR) {
            const uint8_t id = (uint8_t)(rnd() % 16u);
            assert_int_equal(km_parser_take_checksum_error(&by_byte, id),
                             km_parser_take_checksum_error(&by_run, id));
        }
        if (rnd() % 8u == 0u) { /* a poll between runs, at or after the last byte */
            const uint32_t now = s_ticks[i - 1u] + rnd() % (2u * GAP);
            for (;;) {
                const unsigned a = km_parser_poll(&by_byte, now, &copy);
                const unsigned b = km_parser_poll_view(&by_run, now, &out);
                assert_int_equal(a, b);
                if (a & KM_PARSE_CHECKSUM_ERR) {
                    assert_int_equal(km_parser_take_checksum_error(&by_byte, 3),
                                     km_parser_take_checksum_error(&by_run, 3));
                }
                if (!(a & KM_PARSE_FRAME)) {
                    break;
                }
                check_same_frame(&copy, &out.frame);
                frames++;
            }
        }
        check_same_state(&by_byte, &by_run);
    }
    /* The streams are not all noise: many frames came out both ways. */
    assert_true(frames > s_len / 100u);
    assert_true(by_run.stats.checksum_errors > 0u && by_run.stats.timeouts > 0u &&
                by_run.stats.responses_skipped > 0u && by_run.stats.framing_errors > 0u);
}

static void test_s2_s7_batch_equals_byte_by_byte_short_runs(void **state)
{
    (void)state;
    run_stream(0x1234567u, 8u);
}

static void test_s2_s7_batch_equals_byte_by_byte_long_runs(void **state)
{
    (void)state;
    run_stream(0x9E3779B9u, 300u);
    run_stream(0xC0FFEEu, 64u);
}

/* §2: a frame that comes whole in one call is handed out as a view of the
 * caller's bytes; one that comes in pieces is a view into the parser's
 * ring (an empty window restarts at slot 0, so it does not wrap). */
static void test_s2_batch_views(void **state)
{
    (void)state;
    static km_parser_t p;
    static km_parser_out_t out;
    km_parser_init(&p, GAP);
    uint8_t body[KM_BODY_MAX];
    for (size_t i = 0; i < sizeof body; i++) {
        body[i] = (uint8_t)(i * 7u);
    }
    uint8_t f[KM_FRAME_MAX];
    uint32_t ticks[KM_FRAME_MAX] = {0};
    for (unsigned round = 0; round < 20; round++) {
        const size_t blen = 30u + round * 11u;
        const size_t n = rig_command(f, 1, 0x03, body, blen);
        uint32_t used = 0;
        unsigned ev = km_parser_feed_bytes(&p, f, ticks, (uint32_t)n, &used, &out);
        assert_int_equal(ev, KM_PARSE_FRAME);
        assert_int_equal(used, n);
        assert_ptr_equal(out.frame.body, &f[5]);
        /* The same frame again, its first 3 bytes in a call of their own. */
        ev = km_parser_feed_bytes(&p, f, ticks, 3u, &used, &out);
        assert_int_equal(ev, 0u);
        assert_int_equal(used, 3u);
        ev = km_parser_feed_bytes(&p, &f[3], ticks, (uint32_t)(n - 3u), &used, &out);
        assert_int_equal(ev, KM_PARSE_FRAME);
        assert_int_equal(used, n - 3u);
        assert_int_equal(out.frame.body_len, blen);
        assert_memory_equal(out.frame.body, body, blen);
        assert_ptr_equal(out.frame.body, &p.window[5]);
    }
}

/* §2 resync: a good frame found by the rescan of a failed 256-byte
 * candidate, starting near the ring's end, wraps around it: its body is
 * handed out whole, copied into the spill. */
static void test_s2_batch_wrapped_body_in_spill(void **state)
{
    (void)state;
    static km_parser_t p;
    static km_parser_out_t out;
    km_parser_init(&p, GAP);
    uint8_t s[300] = {0};
    uint32_t ticks[300] = {0};
    s[0] = 0xF9; /* an outer candidate of 256 bytes, its checksum wrong */
    s[1] = 0xFF;
    s[2] = 1;
    s[3] = KM_LENGTH_MAX;
    uint8_t inner_body[54];
    for (size_t i = 0; i < sizeof inner_body; i++) {
        inner_body[i] = (uint8_t)(100u + i);
    }
    const size_t inner = rig_command(&s[200], 2, 0x03, inner_body, sizeof inner_body); /* 200..259 */
    assert_int_equal(inner, 60);
    uint32_t used = 0;
    /* Bytes 0..3 alone, so the candidate enters the ring at slot 0. */
    unsigned ev = km_parser_feed_bytes(&p, s, ticks, 4u, &used, &out);
    assert_int_equal(ev, 0u);
    ev = km_parser_feed_bytes(&p, &s[4], ticks, 252u, &used, &out);
    assert_int_equal(used, 252u);
    assert_int_equal(ev, KM_PARSE_CHECKSUM_ERR); /* the outer one fails... */
    assert_int_equal(p.fill, 56u);               /* ...and the inner one waits */
    ev = km_parser_feed_bytes(&p, &s[256], ticks, 4u, &used, &out);
    assert_int_equal(ev, KM_PARSE_FRAME);
    assert_int_equal(used, 4u);
    assert_int_equal(out.frame.id, 2);
    assert_int_equal(out.frame.body_len, sizeof inner_body);
    assert_ptr_equal(out.frame.body, out.spill);
    assert_memory_equal(out.frame.body, inner_body, sizeof inner_body);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s2_s7_batch_equals_byte_by_byte_short_runs),
        cmocka_unit_test(test_s2_s7_batch_equals_byte_by_byte_long_runs),
        cmocka_unit_test(test_s2_batch_views),
        cmocka_unit_test(test_s2_batch_wrapped_body_in_spill),
    };
    return cmocka_run_group_tests_name("parser_batch", tests, NULL, NULL);
}
