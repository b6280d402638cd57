/* SPDX-License-Identifier: Apache-2.0 */
/* Frame parser (docs/protocol.md §2 frames, §7 inter-byte gap): turns received
 * bytes into validated command frames, skips other servos' responses whole,
 * and resynchronises inside the bytes already seen after any failure.
 *
 * How: the unresolved bytes sit in a 256-byte ring (km_parser_t.window), the
 * oldest at `head`. The head byte is always the start of the candidate being
 * judged. A candidate is judged from its first four bytes (F9, FF|F5, ID,
 * length) and, once length+4 bytes are in, from its checksum, which is one
 * subtraction of two prefix sums. If the candidate fails, only its F9 is
 * discarded and the next byte becomes the head: the rescan of the following
 * bytes is the same judging loop, so a good frame inside a failed
 * candidate's length is found from bytes already seen.
 *
 * Two ways in, one rule. km_parser_feed() takes one byte (prv_feed_one, the
 * rule itself). km_parser_feed_bytes(), what the firmware uses, takes a run
 * of bytes from the RX queue and gives the same result as prv_feed_one on
 * each byte in turn (tests/unit/protocol/test_parser_batch.c checks it byte for
 * byte), with three shortcuts where the result is provably the same:
 *  - on an empty window, bytes up to the next F9 are skipped in a tight
 *    loop (the byte rule keeps nothing before an F9);
 *  - a whole frame found in the run, inside the gap, is judged where it
 *    lies (header checks, one sum) and handed out as a view of the
 *    caller's bytes: no copy into the ring, no copy out of it;
 *  - a candidate of known length that spans runs is appended a run at a
 *    time (a store, a prefix-sum store and an add per byte).
 *  Ticks come from one clock and never go backwards, so a stretch of bytes
 *  has no gap when its last tick is within the gap of the tick before it:
 *  the gap rule costs one test per stretch (prv_gapless), not per byte.
 *  Anything else (a header cut by the run's end, a bad header, a checksum
 *  failure, pending or stale bytes) goes the byte way.
 *
 * Work per byte (the bound an interrupt handler can rely on):
 *  - normal path: O(1). A byte that is not F9 on an idle bus returns at once;
 *    a header byte is checked alone (prv_header_grows); a byte inside a
 *    candidate whose length is known is stored and compared with the length
 *    (need); the byte that completes it costs one checksum check and, for a
 *    command frame that wraps around the ring's end, one copy of its body
 *    (<= 250 bytes; otherwise the body is handed out as a view).
 *  - worst case, after a failure: prv_settle() removes at least one byte
 *    from the window per iteration and the window holds at most 256 bytes,
 *    so one call runs at most 257 iterations of O(1) work (four compares and
 *    one prefix-sum subtraction), plus at most one body copy: one scan of
 *    <= 256 bytes. A batch call does the same per byte it consumes, and
 *    stops at the first frame.
 *  - amortised O(1): every byte enters the window once and leaves it once,
 *    and is copied out at most once, so the iterations over a whole stream
 *    are <= bytes fed + calls. A whole frame judged in place is read twice
 *    (header, sum) and never enters the window.
 *  Measured on the bench mix, Cortex-M0 -Os (tools/bench/bench-m0): about 20
 *  instructions per byte through km_parser_feed_bytes in runs of <= 64
 *  bytes (73 byte by byte through the former single-byte path).

 * Only one frame can be handed out per call (there is one `out`), and a
 * call stops at the frame it hands out: bytes after it stay in the window
 * with `pending` set, and the next feed or poll judges them first (so the
 * checksum failures one call reports all precede its frame). The window
 * then cannot overflow: a call that leaves bytes pending has removed the
 * delivered frame (>= 6 bytes), so a pending window holds <= 251 bytes and
 * shrinks by >= 5 per call while frames keep coming out of it; a settled
 * window is one incomplete candidate, <= 255 bytes, so the next byte
 * always fits.
 *
 * A gap longer than gap_ticks (or an overrun) marks every byte in the window
 * stale: complete frames among them are still delivered (they arrived whole),
 * but a candidate that would need a byte from after the cut is dropped.
 *
 * Decisions where the spec is open (see docs/protocol.md):
 *  - F9 followed by anything but FF or F5 is hunting noise, not counted.
 *    After a proper two-byte header, a bad ID or length counts one
 *    framing_error. Command IDs: 0..250, 253, 254. Response IDs: 0..250
 *    (a servo answers with its own ID).
 *  - A response frame with a bad checksum counts a checksum_error but raises
 *    no KM_PARSE_CHECKSUM_ERR and sets no bad_ids bit: status bit 5 is about
 *    commands sent to us.
 *  - end_tick is the tick of the frame's last byte when the frame completes
 *    on its last byte. A frame found by a rescan gets the tick of the newest
 *    byte seen before it was found (before the cut, if a gap or overrun cut
 *    the window): the parser keeps no per-byte ticks, that would be 1 KiB of
 *    RAM. It is never earlier than the true end, so an answer timed from it
 *    cannot overlap the failed candidate's bytes.
 *  - A second cut while frames are still pending drops the bytes received
 *    since the first cut (see prv_cut): rare, and no frame spans a cut.
 *  - timeouts counts a gap once when it makes the parser drop an incomplete
 *    candidate; bytes lost to an overrun are counted in overruns only.
 *  - The gap test is `now - last_tick > gap_ticks` in uint32_t, correct
 *    across wrap-around as long as polls come less than 2^32 ticks apart.
 *
 * Concurrency: one context owns the parser (the UART interrupt, or a main
 * loop fed from a FIFO); km_parser_take_checksum_error() must run in the same
 * context or with that interrupt masked. */
#include "km_parser.h"

#include <stddef.h>
#include <string.h>

_Static_assert(KM_FRAME_MAX == 256u, "the ring is indexed by uint8_t");
_Static_assert(KM_LENGTH_MAX + 4u == KM_FRAME_MAX, "longest frame fills the ring");

typedef enum {
    PRV_INCOMPLETE, /* viable so far, needs more bytes */
    PRV_DROP,       /* not a frame here: discard the head byte */
    PRV_COMMAND,    /* a whole valid command frame at head */
    PRV_RESPONSE,   /* a whole valid response frame at head */
} prv_verdict_t;

static void prv_count(uint32_t *counter)
{
    if (*counter != UINT32_MAX) {
        (*counter)++;
    }
}

static uint8_t prv_at(const km_parser_t *p, uint16_t offset)
{
    return p->window[(uint8_t)(p->head + offset)];
}

static uint8_t prv_psum_at(const km_parser_t *p, uint16_t offset)
{
    return p->psum[(uint8_t)(p->head + offset)];
}

/* Discards the n oldest bytes of the window. */
static void prv_drop(km_parser_t *p, uint16_t n)
{
    p->head = (uint8_t)(p->head + n);
    p->fill = (uint16_t)(p->fill - n);
    if (p->stale > n) {
        p->stale = (uint16_t)(p->stale - n);
    } else {
        p->stale = 0u;
        p->stale_by_gap = false;
    }
}

/* Judges the candidate at head using its first `avail` bytes. Sets *total
 * to the candidate's frame size once its length byte is known. Counts
 * framing and checksum errors; a bad command checksum raises an event. */
static prv_verdict_t prv_judge(km_parser_t *p, uint16_t avail, uint16_t *total, unsigned *events)
{
    if (prv_at(p, 0) != KM_HDR0) {
        return PRV_DROP;
    }
    if (avail < 2u) {
        return PRV_INCOMPLETE;
    }
    const uint8_t kind = prv_at(p, 1);
    if (kind != KM_HDR1_COMMAND && kind != KM_HDR1_RESPONSE) {
        return PRV_DROP;
    }
    if (avail < 3u) {
        return PRV_INCOMPLETE;
    }
    const bool command = (kind == KM_HDR1_COMMAND);
    const uint8_t id = prv_at(p, 2);
    if (command ? !km_id_is_addressable(id) : id > KM_ID_MAX) {
        prv_count(&p->stats.framing_errors);
        return PRV_DROP;
    }
    if (avail < 4u) {
        return PRV_INCOMPLETE;
    }
    const uint8_t length = prv_at(p, 3);
    if (length < KM_LENGTH_MIN || length > KM_LENGTH_MAX) {
        prv_count(&p->stats.framing_errors);
        return PRV_DROP;
    }
    *total = (uint16_t)(length + 4u);
    if (avail < *total) {
        return PRV_INCOMPLETE;
    }
    /* Sum of ID .. last parameter = prefix before the checksum byte minus
     * prefix before the ID (§2). */
    const uint8_t sum = (uint8_t)(prv_psum_at(p, (uint16_t)(*total - 1u)) - prv_psum_at(p, 2));
    const uint8_t want = (uint8_t)~sum;
    if (prv_at(p, (uint16_t)(*total - 1u)) != want) {
        prv_count(&p->stats.checksum_errors);
        if (command) {
            p->bad_ids[id >> 3] = (uint8_t)(p->bad_ids[id >> 3] | (1u << (id & 7u)));
            *events |= KM_PARSE_CHECKSUM_ERR;
        }
        return PRV_DROP;
    }
    return command ? PRV_COMMAND : PRV_RESPONSE;
}

/* Hands the command frame of `total` bytes at head out as a view: its body
 * where it lies in the ring, or, if it wraps around the ring's end, copied
 * whole into out->spill (a frame wraps about once per 256 bytes received). */
static void prv_deliver(const km_parser_t *p, uint16_t total, km_parser_out_t *out)
{
    km_frame_view_t *f = &out->frame;
    const uint8_t len = (uint8_t)(total - 6u); /* header 2, id, len, cmd, checksum */
    f->id = prv_at(p, 2);
    f->body_len = len;
    f->cmd = prv_at(p, 4);
    const uint8_t start = (uint8_t)(p->head + 5u);
    const uint16_t first = (uint16_t)(KM_FRAME_MAX - start);
    if (len <= first) {
        f->body = &p->window[start];
    } else {
        memcpy(out->spill, &p->window[start], first);
        memcpy(&out->spill[first], p->window, (size_t)(len - first));
        f->body = out->spill;
    }
    f->end_tick = p->stale ? p->stale_tick : p->last_tick;
}

/* Judges candidates from head until one is incomplete, the window is empty,
 * or a command frame is handed out. See the bound above. */
static unsigned prv_settle(km_parser_t *p, km_parser_out_t *out)
{
    unsigned events = 0u;
    p->pending = false;
    p->need = 0u;
    while (p->fill > 0u) {
        const uint16_t avail = p->stale ? p->stale : p->fill;
        uint16_t total = 0u;
        switch (prv_judge(p, avail, &total, &events)) {
        case PRV_INCOMPLETE:
            if (p->stale == 0u) {
                p->need = total; /* 0 while the length is unknown */
                return events;
            }
            /* It would need a byte from after the cut. */
            if (p->stale_by_gap) {
                prv_count(&p->stats.timeouts);
                p->stale_by_gap = false;
            }
            prv_drop(p, 1u);
            break;
        case PRV_DROP:
            prv_drop(p, 1u);
            break;
        case PRV_RESPONSE:
            prv_count(&p->stats.responses_skipped);
            prv_drop(p, total);
            break;
        case PRV_COMMAND:
            prv_deliver(p, total, out);
            prv_count(&p->stats.frames_ok);
            prv_drop(p, total);
            /* Stop at the frame: bytes after it are judged by the next call,
             * so a checksum failure this call reports always came before
             * the frame it hands out (the caller judges "was it our ID?"
             * with the ID in force before the frame can change it). */
            p->pending = p->fill > 0u;
            return events | KM_PARSE_FRAME;
        }
    }
    return events;
}

/* Every byte in the window precedes a cut: none may join a later byte.
 * Only one cut is tracked (stale). A second cut can only find bytes after
 * the first one still unjudged while frames wait in `pending` (a settle
 * drains the stale bytes otherwise); those bytes since the first cut are
 * dropped, so no frame can ever span a cut. The price, a frame complete
 * among them is lost, needs two frames hidden in one failed candidate and
 * two cuts before they are handed out. */
static void prv_cut(km_parser_t *p, bool by_gap)
{
    if (p->stale == 0u) {
        p->stale = p->fill;
        p->stale_tick = p->last_tick;
    } else if (p->fill > p->stale) {
        p->fill = p->stale;
    }
    p->stale_by_gap = p->stale_by_gap || by_gap;
    p->need = 0u;
}

/* Fast path for the first four bytes of a candidate: when nothing waits
 * (not pending, no cut), the window before this byte was a viable candidate,
 * so only the byte just stored needs the check prv_judge() would make at its
 * offset. True if it passes; once the length is in, `need` takes over. On
 * false, prv_settle() judges again and counts the error. */
static bool prv_header_grows(km_parser_t *p, uint8_t byte)
{
    switch (p->fill) {
    case 1u:
        return true; /* the F9 checked on entry */
    case 2u:
        return byte == KM_HDR1_COMMAND || byte == KM_HDR1_RESPONSE;
    case 3u:
        return prv_at(p, 1) == KM_HDR1_COMMAND ? km_id_is_addressable(byte) != 0 : byte <= KM_ID_MAX;
    case 4u:
        if (byte < KM_LENGTH_MIN || byte > KM_LENGTH_MAX) {
            return false;
        }
        p->need = (uint16_t)(byte + 4u);
        return true;
    default:
        return false;
    }
}

void km_parser_init(km_parser_t *p, uint32_t gap_ticks)
{
    memset(p, 0, sizeof *p);
    p->gap_ticks = gap_ticks;
}

void km_parser_set_gap(km_parser_t *p, uint32_t gap_ticks)
{
    p->gap_ticks = gap_ticks;
}

/* Stores one byte at the end of the window. */
static inline void prv_push(km_parser_t *p, uint8_t byte, uint32_t now)
{
    if (p->fill == 0u) {
        p->head = 0u; /* see prv_append */
    }
    const uint8_t slot = (uint8_t)(p->head + p->fill);
    p->window[slot] = byte;
    p->psum[slot] = p->acc;
    p->acc = (uint8_t)(p->acc + byte);
    p->fill++;
    p->last_tick = now;
}

/* One byte, the rule every entry follows (the batch entry takes shortcuts
 * only where they give the same result). */
static inline unsigned prv_feed_one(km_parser_t *p, uint8_t byte, uint32_t now, km_parser_out_t *out)
{
    if (p->fill == 0u) {
        if (byte != KM_HDR0) {
            return 0u; /* idle bus, not a header: nothing to keep */
        }
    } else if ((uint32_t)(now - p->last_tick) > p->gap_ticks) {
        prv_cut(p, true);
    }
    prv_push(p, byte, now);
    if (p->fill < p->need) {
        return 0u; /* inside a candidate of known length */
    }
    if (!p->pending && p->stale == 0u && prv_header_grows(p, byte)) {
        return 0u; /* a header byte that keeps the candidate viable */
    }
    return prv_settle(p, out);
}

/* Copies n >= 1 bytes to w[] and their prefix sums to w[KM_FRAME_MAX + i]
 * (psum follows window in km_parser_t); returns the running sum. Its own
 * function, with few live values, so that on ARMv6-M the loop keeps all of
 * them in the eight low registers: a load, two stores, an add, the index
 * step and the loop test per byte. */
__attribute__((noinline)) static uint32_t prv_copy_sum(uint8_t *w, const uint8_t *src, uint32_t n,
                                                       uint32_t acc)
{
    uint8_t *ps = w + KM_FRAME_MAX;
    uint32_t i = 0u;
    do {
        const uint32_t b = src[i];
        w[i] = (uint8_t)b;
        ps[i] = (uint8_t)acc;
        acc += b;
        i++;
    } while (i != n);
    return acc;
}

_Static_assert(offsetof(km_parser_t, psum) == offsetof(km_parser_t, window) + KM_FRAME_MAX,
               "prv_copy_sum finds psum right after window");

/* Appends a run of k >= 1 bytes that stays inside the head candidate's
 * known length, split at the ring's end. */
static void prv_append(km_parser_t *p, const uint8_t *bytes, uint32_t k)
{
    if (p->fill == 0u) {
        /* An empty window may start anywhere: at slot 0 a frame (<= 256
         * bytes) never wraps around the ring's end, and is handed out as a
         * view, not copied into the spill. Only a frame found by a rescan
         * inside a failed candidate can wrap. */
        p->head = 0u;
    }
    const uint8_t slot = (uint8_t)(p->head + p->fill);
    const uint32_t first = KM_FRAME_MAX - slot;
    uint32_t acc = p->acc;
    if (k <= first) {
        acc = prv_copy_sum(&p->window[slot], bytes, k, acc);
    } else {
        acc = prv_copy_sum(&p->window[slot], bytes, first, acc);
        acc = prv_copy_sum(p->window, &bytes[first], k - first, acc);
    }
    p->acc = (uint8_t)acc;
    p->fill = (uint16_t)(p->fill + k);
}

/* The head candidate just became whole (fill == need, nothing pending, no
 * cut): its header was checked byte by byte as it came, so only the
 * checksum is left. A failure goes the general way (prv_settle counts it
 * and rescans). */
static unsigned prv_complete(km_parser_t *p, km_parser_out_t *out)
{
    const uint16_t total = p->need;
    const uint8_t last = (uint8_t)(p->head + total - 1u);
    const uint8_t sum = (uint8_t)(p->psum[last] - p->psum[(uint8_t)(p->head + 2u)]);
    if ((uint8_t)(p->window[last] + sum) != 0xFFu) { /* checksum = ~sum */
        return prv_settle(p, out);
    }
    p->need = 0u;
    p->fill = 0u;
    if (prv_at(p, 1) == KM_HDR1_COMMAND) {
        prv_deliver(p, total, out);
        p->head = (uint8_t)(p->head + total);
        prv_count(&p->stats.frames_ok);
        return KM_PARSE_FRAME;
    }
    p->head = (uint8_t)(p->head + total);
    prv_count(&p->stats.responses_skipped);
    return 0u;
}

/* How many of the k >= 1 bytes whose ticks are ticks[0..k-1] follow one
 * another, and the byte before them (at tick prev), with no gap longer
 * than `gap`. Ticks never go backwards (one clock), so a stride of bytes
 * passes whole when its last tick is within the gap of the tick before the
 * stride: one test per stride, not per byte. A stride that fails is halved;
 * a single byte that fails ends the count. */
static uint32_t prv_gapless(const uint32_t *ticks, uint32_t k, uint32_t prev, uint32_t gap)
{
    uint32_t pos = 0u;
    uint32_t stride = k;
    while (pos < k) {
        uint32_t j = pos + stride;
        if (j > k) {
            j = k;
        }
        const uint32_t t = ticks[j - 1u];
        if ((uint32_t)(t - prev) <= gap) {
            prev = t;
            pos = j;
        } else if (stride > 1u) {
            stride >>= 1;
        } else {
            break;
        }
    }
    return pos;
}

/* A whole viable header at bytes[0..3] (F9 checked by the caller): the
 * checks prv_header_grows() makes byte by byte. Returns the frame size, or
 * 0 if the byte way must judge it. */
static uint32_t prv_header_total(const uint8_t *b)
{
    const uint8_t id = b[2];
    if (b[1] == KM_HDR1_COMMAND) {
        if (!km_id_is_addressable(id)) {
            return 0u;
        }
    } else if (b[1] != KM_HDR1_RESPONSE || id > KM_ID_MAX) {
        return 0u;
    }
    const uint8_t length = b[3];
    if (length < KM_LENGTH_MIN || length > KM_LENGTH_MAX) {
        return 0u;
    }
    return length + 4u;
}

/* Sum of n bytes, four at a time (the checksum of a frame handed out
 * straight from the caller's bytes). */
static uint32_t prv_sum(const uint8_t *b, uint32_t n)
{
    uint32_t sum = 0u;
    const uint8_t *const end4 = b + (n & ~3u);
    while (b != end4) {
        sum += (uint32_t)b[0] + b[1] + b[2] + b[3];
        b += 4;
    }
    for (uint32_t r = n & 3u; r > 0u; r--) {
        sum += *b++;
    }
    return sum;
}

/* A whole frame of `total` bytes at f, all inside the gap, found on an
 * empty window: judged where it lies, with no copy into the ring. True if
 * its checksum holds (then it is handed out as a view of the caller's
 * bytes, or skipped if it is a response); false leaves it to the ring's
 * way, which counts the failure and rescans. The parser's state ends as
 * the ring's way leaves it: window empty, every byte in `acc`, last_tick
 * the frame's last byte. */
static bool prv_whole(km_parser_t *p, const uint8_t *f, uint32_t total, uint32_t end_tick, unsigned *events,
                      km_parser_out_t *out)
{
    const uint32_t sum = prv_sum(&f[2], total - 3u); /* ID .. last parameter */
    const uint8_t check = f[total - 1u];
    if ((uint8_t)(check + sum) != 0xFFu) {
        return false;
    }
    p->acc = (uint8_t)(p->acc + KM_HDR0 + f[1] + sum + check);
    p->last_tick = end_tick;
    if (f[1] == KM_HDR1_COMMAND) {
        km_frame_view_t *v = &out->frame;
        v->id = f[2];
        v->cmd = f[4];
        v->body_len = (uint8_t)(total - 6u);
        v->body = &f[5];
        v->end_tick = end_tick;
        prv_count(&p->stats.frames_ok);
        *events |= KM_PARSE_FRAME;
    } else {
        prv_count(&p->stats.responses_skipped);
    }
    return true;
}

/* What the idle step (window empty) did with the bytes from i. */
typedef enum {
    PRV_IDLE_NEXT,      /* an F9 went into the ring the byte way */
    PRV_IDLE_WHOLE,     /* a whole frame judged where it lies (maybe handed out) */
    PRV_IDLE_CANDIDATE, /* a whole header inside the gap: the run takes it */
} prv_idle_t;

/* Idle, from the F9 at bytes[i]: a whole header already here has its
 * length known before a byte is stored (what the byte way knows after its
 * fourth byte). A whole frame inside the gap is judged where it lies;
 * otherwise the run takes the header into the ring, or the F9 goes the
 * byte way. Returns the next i. Inlined into the batch loop, its only
 * caller. */
static inline __attribute__((always_inline)) uint32_t prv_idle(km_parser_t *p, const uint8_t *bytes,
                                                               const uint32_t *ticks, uint32_t n, uint32_t i,
                                                               unsigned *events, km_parser_out_t *out,
                                                               prv_idle_t *what)
{
    const uint32_t avail = n - i;
    const uint32_t total = avail >= 4u ? prv_header_total(&bytes[i]) : 0u;
    if (total != 0u && total <= avail && prv_gapless(&ticks[i], total, ticks[i], p->gap_ticks) == total &&
        prv_whole(p, &bytes[i], total, ticks[i + total - 1u], events, out)) {
        *what = PRV_IDLE_WHOLE;
        return i + total;
    }
    if (total != 0u && (uint32_t)(ticks[i + 3u] - ticks[i]) <= p->gap_ticks) {
        p->need = (uint16_t)total;
        p->last_tick = ticks[i];
        *what = PRV_IDLE_CANDIDATE;
        return i;
    }
    prv_push(p, KM_HDR0, ticks[i]);
    *what = PRV_IDLE_NEXT;
    return i + 1u;
}

/* Inside a candidate of known length: the bytes of a run toward its end,
 * as long as no gap cuts it (prv_gapless), and never shorter than the
 * rest of a header checked whole by prv_idle; 0 leaves byte i to the byte
 * way (a gap right before it is a cut). *whole: the run completed the
 * candidate (judged, maybe handed out). Inlined into the batch loop. */
static inline __attribute__((always_inline)) uint32_t prv_run(km_parser_t *p, const uint8_t *bytes,
                                                              const uint32_t *ticks, uint32_t n, uint32_t i,
                                                              unsigned *events, km_parser_out_t *out,
                                                              bool *whole)
{
    const uint16_t fill = p->fill;
    if (p->need > fill && !p->pending && p->stale == 0u) {
        const uint32_t k_need = (uint32_t)p->need - fill;
        const uint32_t k_min = fill < 4u ? 4u - fill : 1u;
        const uint32_t k =
            prv_gapless(&ticks[i], k_need < n - i ? k_need : n - i, p->last_tick, p->gap_ticks);
        if (k >= k_min) {
            prv_append(p, &bytes[i], k);
            p->last_tick = ticks[i + k - 1u];
            *whole = k == k_need;
            if (*whole) {
                *events |= prv_complete(p, out);
            }
            return k;
        }
    }
    return 0u;
}

unsigned km_parser_feed_bytes(km_parser_t *p, const uint8_t *bytes, const uint32_t *ticks, uint32_t n,
                              uint32_t *used, km_parser_out_t *out)
{
    uint32_t i = 0u;
    unsigned events = 0u;
    while (i < n) {
        if (p->fill == 0u) {
            /* Idle: skip to the next F9 (no tick matters before it). */
            while (bytes[i] != KM_HDR0) {
                if (++i == n) {
                    *used = n;
                    return events;
                }
            }
            prv_idle_t what;
            i = prv_idle(p, bytes, ticks, n, i, &events, out, &what);
            if (what == PRV_IDLE_NEXT) {
                continue;
            }
            if (what == PRV_IDLE_WHOLE) {
                if (events & KM_PARSE_FRAME) {
                    break;
                }
                continue;
            }
        }
        bool whole = false;
        const uint32_t k = prv_run(p, bytes, ticks, n, i, &events, out, &whole);
        if (k != 0u) {
            i += k;
            if (whole && (events & KM_PARSE_FRAME)) {
                break;
            }
            continue;
        }
        events |= prv_feed_one(p, bytes[i], ticks[i], out);
        i++;
        if (events & KM_PARSE_FRAME) {
            break;
        }
    }
    *used = i;
    return events;
}

/* The legacy entries' copy of a view into a km_frame_t. */
static void prv_copy_out(const km_parser_out_t *v, km_frame_t *out)
{
    out->id = v->frame.id;
    out->cmd = v->frame.cmd;
    out->body_len = v->frame.body_len;
    if (v->frame.body_len > 0u) {
        memcpy(out->body, v->frame.body, v->frame.body_len);
    }
    out->end_tick = v->frame.end_tick;
}

unsigned km_parser_feed(km_parser_t *p, uint8_t byte, uint32_t now, km_frame_t *out)
{
    km_parser_out_t v;
    v.frame = (km_frame_view_t){0}; /* read only after a frame; zeroed for the analyzer */
    const unsigned events = prv_feed_one(p, byte, now, &v);
    if (events & KM_PARSE_FRAME) {
        prv_copy_out(&v, out);
    }
    return events;
}

unsigned km_parser_poll_view(km_parser_t *p, uint32_t now, km_parser_out_t *out)
{
    if (p->fill == 0u) {
        return 0u;
    }
    if ((uint32_t)(now - p->last_tick) > p->gap_ticks) {
        prv_cut(p, true);
    } else if (!p->pending && p->stale == 0u) {
        return 0u; /* a candidate still inside its gap */
    }
    return prv_settle(p, out);
}

unsigned km_parser_poll(km_parser_t *p, uint32_t now, km_frame_t *out)
{
    km_parser_out_t v;
    v.frame = (km_frame_view_t){0}; /* read only after a frame; zeroed for the analyzer */
    const unsigned events = km_parser_poll_view(p, now, &v);
    if (events & KM_PARSE_FRAME) {
        prv_copy_out(&v, out);
    }
    return events;
}

void km_parser_overrun(km_parser_t *p)
{
    prv_count(&p->stats.overruns);
    if (p->fill > 0u) {
        prv_cut(p, false);
    }
}

bool km_parser_take_checksum_error(km_parser_t *p, uint8_t id)
{
    /* Every record is forgotten, not only `id`'s: the caller asks with the
     * ID it has now, and a record kept for another ID would be claimed
     * later by a servo that has since taken that ID (a bad frame for ID 5
     * must not show as bit 5 after an ID change to 5). */
    const bool set = (p->bad_ids[id >> 3] & (1u << (id & 7u))) != 0u;
    memset(p->bad_ids, 0, sizeof p->bad_ids);
    return set;
}
