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
#include <string.h>
#include <cmocka.h>

#include "parser_stream.h"

#define GAP 8u
#define STREAM 200000u

static ps_stream_t s_ps;

/* The next number of the stream's generator, for the test's own draws. */
static uint32_t rnd(void)
{
    return ps_rnd(&s_ps);
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
    ps_make(&s_ps, seed, STREAM, GAP, false);
    km_parser_init(&by_byte, GAP);
    km_parser_init(&by_run, GAP);
    unsigned frames = 0;
    size_t i = 0;
    while (i < s_ps.len) {
        if (s_ps.lost[i]) {
            km_parser_overrun(&by_byte);
            km_parser_overrun(&by_run);
        }
        /* A run stops before the next overrun, as the RX queue's does. */
        uint32_t n = 1u + rnd() % max_run;
        if (n > s_ps.len - i) {
            n = (uint32_t)(s_ps.len - i);
        }
        for (uint32_t k = 1; k < n; k++) {
            if (s_ps.lost[i + k]) {
                n = k;
                break;
            }
        }
        uint32_t used = 0;
        const unsigned ev = km_parser_feed_bytes(&by_run, &s_ps.bytes[i], &s_ps.ticks[i], n, &used, &out);
        assert_true(used >= 1u && used <= n);
        unsigned ev_bytes = 0;
        km_frame_t copy;
        for (uint32_t k = 0; k < used; k++) {
            const unsigned e = km_parser_feed(&by_byte, s_ps.bytes[i + k], s_ps.ticks[i + k], &copy);
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
            const uint32_t now = s_ps.ticks[i - 1u] + rnd() % (2u * GAP);
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
    assert_true(frames > s_ps.len / 100u);
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
 * caller's bytes (the compact form, KM_PROTOCOL_COMPACT: into the ring as
 * every frame); one that comes in pieces is a view into the parser's
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
#if KM_PROTOCOL_COMPACT
        assert_ptr_equal(out.frame.body, &p.window[5]);
#else
        assert_ptr_equal(out.frame.body, &f[5]);
#endif
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

/* The wrapped-frame tests' parser and bytes. */
typedef struct {
    km_parser_t p;
    km_parser_out_t out;
    uint8_t s[300];         /* the bytes on the bus */
    uint32_t ticks[300];    /* their ticks: all 0 */
    uint8_t inner_body[54]; /* the body of the good frame at 200..259 */
    uint32_t used;          /* bytes the last batch call consumed */
} wrap_rig_t;

/* §2 resync set-up of the wrapped-frame tests: in w->s an outer candidate
 * of 256 bytes at 0 (its checksum wrong) and a good 60-byte frame for
 * servo 2 at 200..259; bytes 0..3 fed alone, so the candidate enters the
 * ring at slot 0. */
static void wrapped_setup(wrap_rig_t *w)
{
    memset(w, 0, sizeof *w);
    km_parser_init(&w->p, GAP);
    const uint8_t outer[] = {0xF9, 0xFF, 1, KM_LENGTH_MAX};
    memcpy(w->s, outer, sizeof outer);
    for (size_t i = 0; i < sizeof w->inner_body; i++) {
        w->inner_body[i] = (uint8_t)(100u + i);
    }
    assert_int_equal(rig_command(&w->s[200], 2, 0x03, w->inner_body, sizeof w->inner_body), 60);
    assert_int_equal(km_parser_feed_bytes(&w->p, w->s, w->ticks, 4u, &w->used, &w->out), 0u);
}

/* §2 resync: a good frame found by the rescan of a failed 256-byte
 * candidate, starting near the ring's end, wraps around it: it is handed
 * out whole, as a view at the ring's start (the ring turned, no copy). */
static void test_s2_batch_wrapped_body_turned_to_ring_start(void **state)
{
    (void)state;
    static wrap_rig_t w;
    wrapped_setup(&w);
    unsigned ev = km_parser_feed_bytes(&w.p, &w.s[4], w.ticks, 252u, &w.used, &w.out);
    assert_int_equal(w.used, 252u);
    assert_int_equal(ev, KM_PARSE_CHECKSUM_ERR); /* the outer one fails... */
    assert_int_equal(w.p.fill, 56u);             /* ...and the inner one waits */
    ev = km_parser_feed_bytes(&w.p, &w.s[256], w.ticks, 4u, &w.used, &w.out);
    assert_int_equal(ev, KM_PARSE_FRAME);
    assert_int_equal(w.used, 4u);
    assert_int_equal(w.out.frame.id, 2);
    assert_int_equal(w.out.frame.body_len, sizeof w.inner_body);
    assert_ptr_equal(w.out.frame.body, &w.p.window[5]);
    assert_memory_equal(w.out.frame.body, w.inner_body, sizeof w.inner_body);
}

/* The same with bytes after the wrapped frame already in the ring (a
 * second failed candidate's rescan finds it): turning the ring keeps them
 * and their prefix sums, so the ping after it is handed out next. */
static void test_s2_batch_wrapped_frame_keeps_the_bytes_after_it(void **state)
{
    (void)state;
    static wrap_rig_t w;
    wrapped_setup(&w);
    const uint8_t middle[] = {0xF9, 0xFF, 1, 116}; /* 150..269, checksum wrong */
    memcpy(&w.s[150], middle, sizeof middle);
    assert_int_equal(rig_command(&w.s[260], 3, 0x01, NULL, 0), 6); /* 260..265 */
    unsigned ev = km_parser_feed_bytes(&w.p, &w.s[4], w.ticks, 252u, &w.used, &w.out);
    assert_int_equal(ev, KM_PARSE_CHECKSUM_ERR); /* outer fails, the middle one waits */
    assert_int_equal(w.p.fill, 106u);
    ev = km_parser_feed_bytes(&w.p, &w.s[256], w.ticks, 44u, &w.used, &w.out);
    assert_int_equal(w.used, 14u); /* up to the middle one's end: it fails, the rescan finds the inner one */
    assert_int_equal(ev, KM_PARSE_CHECKSUM_ERR | KM_PARSE_FRAME);
    assert_int_equal(w.out.frame.id, 2);
    assert_int_equal(w.out.frame.cmd, 0x03);
    assert_int_equal(w.out.frame.body_len, sizeof w.inner_body);
    assert_ptr_equal(w.out.frame.body, &w.p.window[5]);
    assert_memory_equal(w.out.frame.body, w.inner_body, sizeof w.inner_body);
    assert_int_equal(w.p.fill, 10u); /* 260..269 wait: the ping and four zeros */
    ev = km_parser_poll_view(&w.p, 0u, &w.out);
    assert_int_equal(ev, KM_PARSE_FRAME);
    assert_int_equal(w.out.frame.id, 3);
    assert_int_equal(w.out.frame.cmd, 0x01);
    assert_int_equal(w.out.frame.body_len, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s2_s7_batch_equals_byte_by_byte_short_runs),
        cmocka_unit_test(test_s2_s7_batch_equals_byte_by_byte_long_runs),
        cmocka_unit_test(test_s2_batch_views),
        cmocka_unit_test(test_s2_batch_wrapped_body_turned_to_ring_start),
        cmocka_unit_test(test_s2_batch_wrapped_frame_keeps_the_bytes_after_it),
    };
    return cmocka_run_group_tests_name("parser_batch", tests, NULL, NULL);
}
