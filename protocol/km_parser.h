/* SPDX-License-Identifier: Apache-2.0 */
/* Frame parser (docs/protocol.md §2, §7 inter-byte gap), fed a byte or a run of
 * bytes at a time.
 *
 * Callable from a UART interrupt: no heap, no recursion, and a stated bound
 * on the work per byte (see km_parser.c). It hunts for F9 FF, validates ID,
 * length and checksum, skips F9 F5 response frames from other servos whole,
 * and after any failure resynchronises at the next possible header inside the
 * bytes already seen, so a good frame right after garbage is never lost.
 * The parser knows no command and no own ID: the dispatcher filters. */
#ifndef KM_PARSER_H
#define KM_PARSER_H

#include <stdbool.h>
#include <stdint.h>

#include "km_frame.h"

/* Diagnostic counters; they saturate rather than wrap. */
typedef struct {
    uint32_t frames_ok;         /* command frames delivered */
    uint32_t responses_skipped; /* whole F9 F5 frames from other servos */
    uint32_t checksum_errors;
    uint32_t framing_errors; /* bad header ID, bad length */
    uint32_t timeouts;       /* partial frames dropped by the gap */
    uint32_t overruns;       /* bytes the caller reported lost */
} km_parser_stats_t;

/* Events returned by feed/poll, as a bitmask (one call can both finish a
 * checksum failure and, from the bytes already seen, a good frame). */
#define KM_PARSE_FRAME 0x01u        /* *out holds a new command frame */
#define KM_PARSE_CHECKSUM_ERR 0x02u /* see km_parser_take_checksum_error() */

typedef struct {
    /* The scalars first: on ARMv6-M a load or store reaches a byte field at
     * offset <= 31, a halfword <= 62 and a word <= 124 from the struct
     * pointer in one instruction; behind the arrays each would need the
     * offset built in a register first. */
    uint8_t head;        /* ring index of the oldest byte */
    uint8_t acc;         /* sum mod 256 of every byte fed */
    bool pending;        /* bytes after a delivered frame wait to be judged */
    bool stale_by_gap;   /* the stale cut was a gap: count a timeout */
    uint16_t fill;       /* bytes in window (0..256) */
    uint16_t need;       /* bytes the head candidate needs; 0 = re-judge */
    uint16_t stale;      /* leading bytes cut off by a gap or overrun */
    uint32_t last_tick;  /* tick of the newest byte */
    uint32_t stale_tick; /* tick of the newest stale byte */
    uint32_t gap_ticks;  /* inter-byte gap that drops a frame */
    km_parser_stats_t stats;
    uint8_t bad_ids[32]; /* bitset: IDs seen on checksum-failed frames */
    /* A 256-byte ring indexed by uint8_t, so wrap-around is free: the bytes
     * not yet resolved, oldest at `head` (a candidate's F9, or bytes still to
     * rescan after a failure). A frame is at most 256 bytes, so one ring
     * always holds a whole candidate. */
    uint8_t window[KM_FRAME_MAX];
    /* psum[i]: sum mod 256 of every byte fed before window[i]; the checksum
     * of any candidate inside the ring is then one subtraction. */
    uint8_t psum[KM_FRAME_MAX];
} km_parser_t;

/* Where the batch entries hand a frame out: a view. frame.body points into
 * the caller's bytes (a frame that came whole in one run: judged where it
 * lies), into the parser's ring (a frame that spanned calls), or into
 * `spill`, where the body of the rare frame that wraps around the ring's
 * end (one found by a rescan inside a failed candidate) is copied so that
 * a view is always one contiguous run. Valid until the next call on the
 * parser and while the caller's bytes stay put. */
typedef struct {
    km_frame_view_t frame;
    uint8_t spill[KM_BODY_MAX];
} km_parser_out_t;

void km_parser_init(km_parser_t *p, uint32_t gap_ticks);
void km_parser_set_gap(km_parser_t *p, uint32_t gap_ticks);

/* One received byte at tick `now`. Returns KM_PARSE_* bits; *out is written
 * only when KM_PARSE_FRAME is set (a copy: see km_parser_feed_bytes for the
 * entry the firmware uses). */
unsigned km_parser_feed(km_parser_t *p, uint8_t byte, uint32_t now, km_frame_t *out);

/* Batch entry: the same as km_parser_feed() on bytes[0], bytes[1], ... with
 * ticks[0], ticks[1], ..., stopping after the byte on which a frame is
 * handed out; *used = the bytes consumed (>= 1 when n >= 1), and the result
 * is every event of those bytes OR-ed (the checksum failures all precede
 * the frame, as with km_parser_feed). The frame is handed out as a view
 * (out->frame, see km_parser_out_t): hand it on before releasing `bytes`.
 * Ticks must not go backwards inside one call (they come from one clock):
 * the gap rule is then checked once per stretch of bytes, not per byte. */
unsigned km_parser_feed_bytes(km_parser_t *p, const uint8_t *bytes, const uint32_t *ticks, uint32_t n,
                              uint32_t *used, km_parser_out_t *out);

/* Time alone: drops a partial frame once the gap has passed in silence
 * (handing out any whole frame found inside it), and hands out a frame found
 * by a resync that an earlier call had no room for. Call it until the result
 * lacks KM_PARSE_FRAME to drain them. */
unsigned km_parser_poll(km_parser_t *p, uint32_t now, km_frame_t *out);

/* km_parser_poll() handing the frame out as a view, like km_parser_feed_bytes. */
unsigned km_parser_poll_view(km_parser_t *p, uint32_t now, km_parser_out_t *out);

/* The caller (UART driver) lost bytes: the partial frame is dropped. */
void km_parser_overrun(km_parser_t *p);

/* True if a checksum-failed command frame since the last call carried ID
 * `id`. Forgets every ID's record, so call it after every feed or poll that
 * returned KM_PARSE_CHECKSUM_ERR, with the ID in force at that moment. The
 * failures a call reports all precede the frame it delivers (if any). */
bool km_parser_take_checksum_error(km_parser_t *p, uint8_t id);

/* Default inter-byte gap in microseconds at a baud rate: 10 byte times, but
 * never under 1 ms, so a USB-serial master that splits a frame across USB
 * packets is not cut (resync makes a long gap cheap: see km_parser.c). */
static inline uint32_t km_parser_default_gap_us(uint32_t baud)
{
    uint32_t ten_bytes_us = (100u * 1000000u) / (baud ? baud : 1u);
    return ten_bytes_us > 1000u ? ten_bytes_us : 1000u;
}

#endif
