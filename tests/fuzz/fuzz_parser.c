/* SPDX-License-Identifier: Apache-2.0 */
/* libFuzzer target for the frame parser (docs/protocol.md §2 frames, §7 gap).
 *
 * Input: byte 0 sets gap_ticks (0..15), byte 1 the start tick near the
 * uint32_t wrap; then (byte, control) pairs. The control byte's top bits
 * pick what happens before the byte is fed:
 *   00xxxxxx  advance the tick by xxxxxx (0..63), then feed
 *   01xxxxxx  advance the tick by xxxxxx and poll (drains pending frames),
 *             then feed
 *   10xxxxxx  report an overrun, then feed
 *   11xxxxxx  jump the tick by xxxxxx * 2^26 (wrap-around), then feed
 * A trailing odd byte is fed as is. Finally the parser is polled past the gap
 * until it has nothing left.
 *
 * Invariants (abort() on violation):
 *  - a delivered frame has body_len <= KM_BODY_MAX and an addressable ID;
 *  - re-encoded (F9 FF id len cmd body cs) it appears, checksum right, in
 *    the bytes fed, all inside one run without a gap or overrun, and ending
 *    at or before the byte just fed;
 *  - end_tick is the tick of the frame's last byte or of a later byte;
 *  - counters never decrease; frames_ok counts the frames handed out; a
 *    checksum event comes with a checksum_errors increment and exactly then
 *    an addressable ID is recorded for km_parser_take_checksum_error();
 *  - the window holds at most 256 bytes, and after the final polls it is
 *    empty with nothing pending;
 *  - a second parser fed the same bytes through the batch entry
 *    (km_parser_feed_bytes, in runs between polls, overruns and tick jumps,
 *    as the app feeds it from the RX queue) hands out the same frames
 *    (fields, body, end_tick), keeps the same counters and the same
 *    window, at every run's end. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "km_parser.h"

#define HISTORY_MAX 8192u

static uint8_t s_hist[HISTORY_MAX];  /* bytes fed */
static uint32_t s_run[HISTORY_MAX];  /* run number of each byte (cut by gap/overrun) */
static uint32_t s_tick[HISTORY_MAX]; /* tick each byte was fed at */
static size_t s_hist_len;
static km_parser_stats_t s_prev;
static uint32_t s_delivered;

/* The batch side: the bytes and ticks of the current run, the parser they
 * go to, and a hash of the frames each parser handed out, in order. */
static km_parser_t s_q;
static km_parser_out_t s_q_out;
static uint8_t s_run_bytes[HISTORY_MAX];
static uint32_t s_run_ticks[HISTORY_MAX];
static size_t s_run_len;
static uint32_t s_hash_bytewise;
static uint32_t s_hash_batch;

static uint32_t prv_hash(uint32_t h, uint8_t id, uint8_t cmd, uint8_t len, const uint8_t *body,
                         uint32_t end_tick)
{
    const uint8_t head[7] = {id,
                             cmd,
                             len,
                             (uint8_t)end_tick,
                             (uint8_t)(end_tick >> 8),
                             (uint8_t)(end_tick >> 16),
                             (uint8_t)(end_tick >> 24)};
    for (size_t i = 0; i < sizeof head; i++) {
        h = (h ^ head[i]) * 16777619u; /* FNV-1a */
    }
    for (size_t i = 0; i < len; i++) {
        h = (h ^ body[i]) * 16777619u;
    }
    return h;
}

/* Aborts with the line of the broken invariant, for the crash report. */
#define prv_check(ok) prv_check_at((ok), __LINE__)
static void prv_check_at(int ok, int line)
{
    if (!ok) {
        fprintf(stderr, "fuzz_parser: invariant at line %d broken\n", line);
        abort();
    }
}

static void prv_check_stats(const km_parser_t *p, unsigned ev)
{
    const km_parser_stats_t *s = &p->stats;
    prv_check(s->frames_ok >= s_prev.frames_ok);
    prv_check(s->responses_skipped >= s_prev.responses_skipped);
    prv_check(s->checksum_errors >= s_prev.checksum_errors);
    prv_check(s->framing_errors >= s_prev.framing_errors);
    prv_check(s->timeouts >= s_prev.timeouts);
    prv_check(s->overruns >= s_prev.overruns);
    if (ev & KM_PARSE_CHECKSUM_ERR) {
        prv_check(s->checksum_errors > s_prev.checksum_errors);
    }
    prv_check(s->frames_ok == s_delivered);
    prv_check(p->fill <= KM_FRAME_MAX);
    s_prev = *s;
}

/* The frame, re-encoded, must sit in the history inside one run. */
static int prv_tick_at_or_after(size_t from, uint32_t tick)
{
    for (size_t k = from; k < s_hist_len; k++) {
        if (s_tick[k] == tick) {
            return 1;
        }
    }
    return 0;
}

static void prv_check_frame(const km_frame_t *f)
{
    prv_check(f->body_len <= KM_BODY_MAX);
    prv_check(km_id_is_addressable(f->id));

    uint8_t enc[KM_FRAME_MAX];
    const size_t n = 6u + f->body_len;
    enc[0] = KM_HDR0;
    enc[1] = KM_HDR1_COMMAND;
    enc[2] = f->id;
    enc[3] = (uint8_t)(f->body_len + 2u);
    enc[4] = f->cmd;
    memcpy(&enc[5], f->body, f->body_len);
    enc[n - 1u] = km_checksum(&enc[2], (uint32_t)(n - 3u));

    for (size_t start = 0; start + n <= s_hist_len; start++) {
        if (s_run[start] == s_run[start + n - 1u] && memcmp(&s_hist[start], enc, n) == 0 &&
            prv_tick_at_or_after(start + n - 1u, f->end_tick)) {
            return;
        }
    }
    prv_check(0); /* not fed as one run, or end_tick not a tick from its end on */
}

/* A checksum event leaves at least one ID recorded, every one of them
 * addressable; taking (with any ID) forgets them all. */
static void prv_check_bad_ids(km_parser_t *p, unsigned ev)
{
    static const uint8_t none[sizeof p->bad_ids];
    if (!(ev & KM_PARSE_CHECKSUM_ERR)) {
        prv_check(memcmp(p->bad_ids, none, sizeof none) == 0); /* cheap path */
        return;
    }
    int recorded = 0;
    for (unsigned id = 0; id <= 255u; id++) {
        if (p->bad_ids[id >> 3] & (1u << (id & 7u))) {
            prv_check(km_id_is_addressable((uint8_t)id));
            recorded = 1;
        }
    }
    prv_check(recorded);
    (void)km_parser_take_checksum_error(p, 0);
    prv_check(memcmp(p->bad_ids, none, sizeof none) == 0);
}

static void prv_take(km_parser_t *p, unsigned ev, const km_frame_t *f)
{
    if (ev & KM_PARSE_FRAME) {
        s_delivered++;
        prv_check_frame(f);
        s_hash_bytewise = prv_hash(s_hash_bytewise, f->id, f->cmd, f->body_len, f->body, f->end_tick);
    }
    prv_check_stats(p, ev);
    prv_check_bad_ids(p, ev);
}

/* The batch parser takes the run so far, a call at a time (each stops at
 * the frame it hands out), then both parsers must agree. */
static void prv_batch_flush(const km_parser_t *p)
{
    size_t i = 0;
    while (i < s_run_len) {
        uint32_t used = 0;
        const unsigned ev = km_parser_feed_bytes(&s_q, &s_run_bytes[i], &s_run_ticks[i],
                                                 (uint32_t)(s_run_len - i), &used, &s_q_out);
        prv_check(used >= 1u && used <= s_run_len - i);
        prv_check(!(ev & KM_PARSE_FRAME) || s_q_out.frame.body_len <= KM_BODY_MAX);
        if (ev & KM_PARSE_FRAME) {
            const km_frame_view_t *v = &s_q_out.frame;
            s_hash_batch = prv_hash(s_hash_batch, v->id, v->cmd, v->body_len, v->body, v->end_tick);
        }
        if (ev & KM_PARSE_CHECKSUM_ERR) {
            (void)km_parser_take_checksum_error(&s_q, 0);
        }
        i += used;
    }
    s_run_len = 0;
    prv_check(s_hash_batch == s_hash_bytewise);
    prv_check(memcmp(&s_q.stats, &p->stats, sizeof p->stats) == 0);
    prv_check(s_q.fill == p->fill && s_q.need == p->need && s_q.stale == p->stale &&
              s_q.pending == p->pending && s_q.last_tick == p->last_tick);
    for (unsigned k = 0; k < p->fill; k++) {
        prv_check(s_q.window[(uint8_t)(s_q.head + k)] == p->window[(uint8_t)(p->head + k)]);
    }
}

/* A poll on the batch parser, as on the byte parser. */
static void prv_batch_poll(uint32_t now)
{
    unsigned ev;
    do {
        ev = km_parser_poll_view(&s_q, now, &s_q_out);
        if (ev & KM_PARSE_FRAME) {
            const km_frame_view_t *v = &s_q_out.frame;
            s_hash_batch = prv_hash(s_hash_batch, v->id, v->cmd, v->body_len, v->body, v->end_tick);
        }
        if (ev & KM_PARSE_CHECKSUM_ERR) {
            (void)km_parser_take_checksum_error(&s_q, 0);
        }
    } while (ev & KM_PARSE_FRAME);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static km_parser_t p;
    km_frame_t f;
    if (size < 2u) {
        return 0;
    }
    km_parser_init(&p, data[0] & 15u);
    uint32_t now = 0xFFFFFF00u + (uint32_t)data[1];
    uint32_t newest = now;
    uint32_t run = 0;
    s_hist_len = 0;
    s_delivered = 0;
    memset(&s_prev, 0, sizeof s_prev);
    km_parser_init(&s_q, data[0] & 15u);
    s_run_len = 0;
    s_hash_bytewise = 2166136261u;
    s_hash_batch = 2166136261u;

    for (size_t i = 2; i < size && s_hist_len < HISTORY_MAX; i += 2u) {
        const uint8_t byte = data[i];
        const uint8_t ctl = (i + 1u < size) ? data[i + 1u] : 0u;
        const uint32_t arg = ctl & 0x3Fu;
        switch (ctl >> 6) {
        case 0:
            now += arg;
            break;
        case 1: {
            unsigned ev;
            now += arg;
            prv_batch_flush(&p);
            do {
                memset(&f, 0, sizeof f);
                ev = km_parser_poll(&p, now, &f);
                prv_take(&p, ev, &f);
            } while (ev & KM_PARSE_FRAME);
            prv_batch_poll(now);
            break;
        }
        case 2:
            prv_batch_flush(&p);
            km_parser_overrun(&p);
            km_parser_overrun(&s_q);
            run++;
            break;
        default:
            /* A jump of up to 2^32 ticks: one call's ticks must come from
             * a clock that does not go round, so a new run starts. */
            prv_batch_flush(&p);
            now += arg << 26;
            break;
        }
        if (s_hist_len > 0u && (uint32_t)(now - newest) > p.gap_ticks) {
            run++; /* the parser must not join bytes across this gap */
        }
        s_hist[s_hist_len] = byte;
        s_run[s_hist_len] = run;
        s_tick[s_hist_len] = now;
        s_hist_len++;
        newest = now;
        memset(&f, 0, sizeof f);
        prv_take(&p, km_parser_feed(&p, byte, now, &f), &f);
        s_run_bytes[s_run_len] = byte;
        s_run_ticks[s_run_len] = now;
        s_run_len++;
    }
    prv_batch_flush(&p);

    /* Silence past the gap: everything must resolve. */
    unsigned ev;
    int guard = 0;
    do {
        ev = km_parser_poll(&p, newest + p.gap_ticks + 1u, &f);
        prv_take(&p, ev, &f);
        prv_check(++guard < 300);
    } while (ev & KM_PARSE_FRAME);
    prv_check(p.fill == 0u && !p.pending);
    prv_batch_poll(newest + p.gap_ticks + 1u);
    prv_check(s_hash_batch == s_hash_bytewise);
    prv_check(memcmp(&s_q.stats, &p.stats, sizeof p.stats) == 0);
    prv_check(s_q.fill == 0u && !s_q.pending);
    return 0;
}
