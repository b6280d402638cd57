/* SPDX-License-Identifier: Apache-2.0 */
/* Frame parser (docs/protocol.md §2 frames, §7 inter-byte gap): received bytes to validated command frames;
 * other servos' responses skipped whole; resynchronised inside the bytes already seen. How it works, its work
 * per byte and its decisions: docs/architecture.md "Inside the parser". */
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
    /* Checksum (§2): prefix sum before the checksum byte minus prefix sum before the ID. */
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

/* Turns the 256-byte ring so that ring[i] takes the byte at ring[(i + k) mod 256]: one pass per cycle of the
 * permutation (gcd(k, 256) of them, k's lowest set bit), every byte moved once. */
static void prv_rotate(uint8_t *ring, uint32_t k)
{
    const uint32_t cycles = k & (0u - k);
    for (uint32_t c = 0u; c < cycles; c++) {
        const uint8_t first = ring[c];
        uint32_t i = c;
        uint32_t next = (c + k) & (KM_FRAME_MAX - 1u);
        while (next != c) {
            ring[i] = ring[next];
            i = next;
            next = (next + k) & (KM_FRAME_MAX - 1u);
        }
        ring[i] = first;
    }
}

/* Hands the command frame at head out: a view in the ring. A frame that wraps around the ring's end (only one
 * found by a rescan) is first turned to slot 0 with every byte after it, window and prefix sums alike. */
static void prv_deliver(km_parser_t *p, uint16_t total, km_parser_out_t *out)
{
    if ((uint32_t)p->head + total > KM_FRAME_MAX) {
        prv_rotate(p->window, p->head);
        prv_rotate(p->psum, p->head);
        p->head = 0u;
    }
    km_frame_view_t *f = &out->frame;
    f->id = prv_at(p, 2);
    f->body_len = (uint8_t)(total - 6u); /* header 2, id, len, cmd, checksum */
    f->cmd = prv_at(p, 4);
    f->body = &p->window[(uint8_t)(p->head + 5u)];
    f->end_tick = p->stale ? p->stale_tick : p->last_tick;
}

/* Judges candidates from head until one is incomplete, the window is empty, or a frame is handed out. */
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
            /* Stop at the frame: later bytes wait for the next call. */
            p->pending = p->fill > 0u;
            return events | KM_PARSE_FRAME;
        }
    }
    return events;
}

/* Marks every byte in the window as before a cut (a second cut drops the bytes since the first). */
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

/* Fast header check of the byte just stored (false: prv_settle() judges again). */
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

/* One byte, the rule every entry follows. */
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

#if !KM_PROTOCOL_COMPACT
/* Copies n >= 1 bytes to w[] and their prefix sums to w[KM_FRAME_MAX + i]; returns the running sum. */
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

/* Appends a run of k >= 1 bytes inside the head candidate's known length, split at the ring's end. */
static void prv_append(km_parser_t *p, const uint8_t *bytes, uint32_t k)
{
    if (p->fill == 0u) {
        /* An empty window restarts at slot 0: a frame from it never wraps. */
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

/* The head candidate just became whole: only its checksum is left to check. */
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

/* How many of the k >= 1 bytes ticks[0..k-1] follow tick prev with no gap longer than `gap`. */
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

/* Frame size of a whole viable header at bytes[0..3], or 0 for the byte way. */
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

/* Sum of n bytes, four at a time. */
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

/* Judges a whole frame at f in place (empty window, inside the gap); false: the ring's way. */
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

/* Idle, from the F9 at bytes[i]: judges a whole frame in place or starts a candidate; returns the next i. */
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

/* Inside a candidate of known length: takes the run's bytes toward its end (0: byte i goes the byte way). */
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

#endif

#if KM_PROTOCOL_COMPACT
_Static_assert(KM_PARSE_FRAME == 1u, "prv_rest_here returns the event in bit 0");

/* The head candidate's length known and the rest of it in the caller's n >= 1 bytes b[]: stored after it in
 * the ring and, with no gap and a good checksum, judged at once (a command handed out as prv_settle() would).
 * Returns the bytes taken * 2 + KM_PARSE_FRAME if a command, or 0 for the byte way. */
__attribute__((noinline)) static uint32_t
prv_rest_here(km_parser_t *p, const uint8_t *b, const uint32_t *ticks, uint32_t n, km_parser_out_t *out)
{
    const uint32_t k = (uint32_t)p->need - p->fill;
    if (k > n) {
        return 0u;
    }
    /* the ID onward already fed (acc less the prefix sum before the ID), then the rest with the checksum */
    const uint32_t before_id = prv_psum_at(p, 2u);
    uint32_t sum = p->acc - before_id;
    uint32_t prev = p->last_tick;
    const uint32_t slot = (uint32_t)p->head + p->fill;
    for (uint32_t j = 0u; j < k; j++) {
        if ((uint32_t)(ticks[j] - prev) > p->gap_ticks) {
            return 0u;
        }
        prev = ticks[j];
        sum += b[j];
        p->window[(uint8_t)(slot + j)] = b[j]; /* past fill: the byte way stores it again if need be */
    }
    if ((uint8_t)sum != 0xFFu) {
        return 0u;
    }
    p->acc = (uint8_t)(before_id + sum);
    p->last_tick = prev;
    const uint16_t total = p->need;
    p->fill = 0u;
    p->need = 0u;
    if (prv_at(p, 1u) != KM_HDR1_COMMAND) {
        prv_count(&p->stats.responses_skipped);
        return k * 2u;
    }
    prv_deliver(p, total, out);
    prv_count(&p->stats.frames_ok);
    return k * 2u + KM_PARSE_FRAME;
}
#endif

unsigned km_parser_feed_bytes(km_parser_t *p, const uint8_t *bytes, const uint32_t *ticks, uint32_t n,
                              uint32_t *used, km_parser_out_t *out)
{
    uint32_t i = 0u;
    unsigned events = 0u;
#if KM_PROTOCOL_COMPACT
    bool refused = false; /* prv_rest_here said no: byte way to the candidate's end */
    while (i < n && (events & KM_PARSE_FRAME) == 0u) {
        const uint32_t whole =
            !refused && p->need > p->fill ? prv_rest_here(p, &bytes[i], &ticks[i], n - i, out) : 0u;
        refused = whole == 0u && p->need > p->fill;
        if (whole != 0u) {
            events |= whole & KM_PARSE_FRAME;
            i += whole >> 1;
            continue;
        }
        events |= prv_feed_one(p, bytes[i], ticks[i], out);
        i++;
    }
#else
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
#endif
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
    /* Every record is forgotten, not only `id`'s (docs/architecture.md "Inside the parser"). */
    const bool set = (p->bad_ids[id >> 3] & (1u << (id & 7u))) != 0u;
    memset(p->bad_ids, 0, sizeof p->bad_ids);
    return set;
}

void km_rx_track_sync(km_rx_track_t *t, const km_parser_t *p)
{
    if (p->fill == 0u) {
        t->state = KM_TRACK_HUNT;
    } else if (p->pending || p->stale != 0u) {
        t->state = KM_TRACK_EVERY;
    } else if (p->need > p->fill) {
        t->state = KM_TRACK_COUNT;
        t->left = (uint16_t)(p->need - p->fill);
    } else if (p->fill == 1u) {
        t->state = KM_TRACK_F9; /* a settled window starts with a viable header */
    } else if (p->fill == 2u) {
        t->state = prv_at(p, 1) == KM_HDR1_COMMAND ? KM_TRACK_COMMAND : KM_TRACK_RESPONSE;
    } else if (p->fill == 3u) {
        t->state = KM_TRACK_ID;
    } else {
        t->state = KM_TRACK_EVERY;
    }
}
