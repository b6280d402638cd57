/* Frame parser (PROTOCOL.md §2 frames, §7 inter-byte gap): turns received
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
 * Work per byte (the bound an interrupt handler can rely on):
 *  - normal path: O(1). A byte that is not F9 on an idle bus returns at once;
 *    a header byte is checked alone (prv_header_grows); a byte inside a
 *    candidate whose length is known is stored and compared with the length
 *    (need); the byte that completes it costs one checksum check and, for a
 *    command frame, one copy of its body (<= 250 bytes).
 *  - worst case, after a failure: prv_settle() removes at least one byte
 *    from the window per iteration and the window holds at most 256 bytes,
 *    so one call runs at most 257 iterations of O(1) work (four compares and
 *    one prefix-sum subtraction), plus at most one body copy: one scan of
 *    <= 256 bytes.
 *  - amortised O(1): every byte enters the window once and leaves it once,
 *    and is copied out at most once, so the iterations over a whole stream
 *    are <= bytes fed + calls.
 *  Measured on the bench mix (tools/bench-parser): about 42 instructions per
 *  byte at -O2 on x86-64; 978 bytes of Cortex-M0 code at -Os.
 *
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
 * Decisions where the spec is open (see PROTOCOL.md):
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
static prv_verdict_t prv_judge(km_parser_t *p, uint16_t avail, uint16_t *total,
                               unsigned *events)
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

/* Copies the command frame of `total` bytes at head into *out. */
static void prv_deliver(const km_parser_t *p, uint16_t total, km_frame_t *out)
{
    out->id = prv_at(p, 2);
    out->body_len = (uint8_t)(total - 6u); /* header 2, id, len, cmd, checksum */
    out->cmd = prv_at(p, 4);
    /* The body may wrap around the end of the ring: at most two copies. */
    const uint8_t start = (uint8_t)(p->head + 5u);
    const uint16_t first = (uint16_t)(KM_FRAME_MAX - start);
    if (out->body_len <= first) {
        memcpy(out->body, &p->window[start], out->body_len);
    } else {
        memcpy(out->body, &p->window[start], first);
        memcpy(&out->body[first], p->window, (size_t)(out->body_len - first));
    }
    out->end_tick = p->stale ? p->stale_tick : p->last_tick;
}

/* Judges candidates from head until one is incomplete, the window is empty,
 * or a command frame is handed out. See the bound above. */
static unsigned prv_settle(km_parser_t *p, km_frame_t *out)
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
        return prv_at(p, 1) == KM_HDR1_COMMAND ? km_id_is_addressable(byte) != 0
                                               : byte <= KM_ID_MAX;
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

unsigned km_parser_feed(km_parser_t *p, uint8_t byte, uint32_t now, km_frame_t *out)
{
    if (p->fill == 0u) {
        if (byte != KM_HDR0) {
            return 0u; /* idle bus, not a header: nothing to keep */
        }
    } else if ((uint32_t)(now - p->last_tick) > p->gap_ticks) {
        prv_cut(p, true);
    }
    const uint8_t slot = (uint8_t)(p->head + p->fill);
    p->window[slot] = byte;
    p->psum[slot] = p->acc;
    p->acc = (uint8_t)(p->acc + byte);
    p->fill++;
    p->last_tick = now;
    if (p->fill < p->need) {
        return 0u; /* inside a candidate of known length */
    }
    if (!p->pending && p->stale == 0u && prv_header_grows(p, byte)) {
        return 0u; /* a header byte that keeps the candidate viable */
    }
    return prv_settle(p, out);
}

unsigned km_parser_poll(km_parser_t *p, uint32_t now, km_frame_t *out)
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
