/* SPDX-License-Identifier: Apache-2.0 */
/* Frame parser (docs/protocol.md §2, §7 inter-byte gap), fed a byte or a run of bytes at a time; callable
 * from a UART interrupt (docs/architecture.md "Inside the parser"). */
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
    /* The scalars first: reachable in one ARMv6-M load or store. */
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
    /* The unresolved bytes, oldest at `head`: a 256-byte ring indexed by uint8_t. */
    uint8_t window[KM_FRAME_MAX];
    /* psum[i]: sum mod 256 of every byte fed before window[i]; the checksum
     * of any candidate inside the ring is then one subtraction. */
    uint8_t psum[KM_FRAME_MAX];
} km_parser_t;

/* A frame handed out by the batch entries: a view, valid until the next call on the parser. */
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

/* Batch entry: km_parser_feed() on bytes[0..n-1] in turn, stopping at a frame; *used = bytes consumed. */
unsigned km_parser_feed_bytes(km_parser_t *p, const uint8_t *bytes, const uint32_t *ticks, uint32_t n,
                              uint32_t *used, km_parser_out_t *out);

/* Time alone: drops a partial frame after a silent gap, hands out a waiting frame; call until no
 * KM_PARSE_FRAME. */
unsigned km_parser_poll(km_parser_t *p, uint32_t now, km_frame_t *out);

/* km_parser_poll() handing the frame out as a view, like km_parser_feed_bytes. */
unsigned km_parser_poll_view(km_parser_t *p, uint32_t now, km_parser_out_t *out);

/* The caller (UART driver) lost bytes: the partial frame is dropped. */
void km_parser_overrun(km_parser_t *p);

/* True if a checksum-failed command frame since the last call carried ID `id`; forgets every ID's record. */
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
