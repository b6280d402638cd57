/* SPDX-License-Identifier: Apache-2.0 */
/* Frame parser (docs/protocol.md §2, §7 inter-byte gap), fed a byte or a run of bytes at a time; callable
 * from a UART interrupt (docs/architecture.md "Inside the parser"). */
#ifndef KM_PARSER_H
#define KM_PARSER_H

#include <stdbool.h>
#include <stdint.h>

#include "km_frame.h"

/* KM_PROTOCOL_COMPACT=1 (the 32 KiB STM32G031F6 build, docs/footprint.md): the batch entry feeds its bytes to
 * the byte rule one by one (the rest of a candidate of known length in one loop), every frame a view into the
 * ring; 0: whole frames are judged in place and runs appended in bulk (fewer instructions, more code). */
#ifndef KM_PROTOCOL_COMPACT
#define KM_PROTOCOL_COMPACT 0
#endif

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
    /* The unresolved bytes, oldest at `head`: a 256-byte ring indexed by uint8_t. */
    uint8_t window[KM_FRAME_MAX];
    /* psum[i]: sum mod 256 of every byte fed before window[i]; the checksum
     * of any candidate inside the ring is then one subtraction. */
    uint8_t psum[KM_FRAME_MAX];
    km_parser_stats_t stats;
    uint8_t bad_ids[32]; /* bitset: IDs seen on checksum-failed frames */
} km_parser_t;

/* A frame handed out by the batch entries: a view, valid until the next call on the parser. */
typedef struct {
    km_frame_view_t frame;
} km_parser_out_t;

void km_parser_init(km_parser_t *p, uint32_t gap_ticks);
void km_parser_set_gap(km_parser_t *p, uint32_t gap_ticks);

/* One received byte at tick `now`. Returns KM_PARSE_* bits; *out is written
 * only when KM_PARSE_FRAME is set (a copy: see km_parser_feed_bytes for the
 * entry the firmware uses). */
unsigned km_parser_feed(km_parser_t *p, uint8_t byte, uint32_t now, km_frame_t *out);

/* Batch entry: km_parser_feed() on bytes[0..n-1] in turn, stopping at a frame; *used = bytes consumed. A
 * frame that came whole in this call may be a view of `bytes` (not with KM_PROTOCOL_COMPACT). */
unsigned km_parser_feed_bytes(km_parser_t *p, const uint8_t *bytes, const uint32_t *ticks, uint32_t n,
                              uint32_t *used, km_parser_out_t *out);

/* Time alone: drops a partial frame after a silent gap, hands out a waiting frame; call until no
 * KM_PARSE_FRAME. */
unsigned km_parser_poll(km_parser_t *p, uint32_t now, km_frame_t *out);

/* km_parser_poll() handing the frame out as a view, like km_parser_feed_bytes. */
unsigned km_parser_poll_view(km_parser_t *p, uint32_t now, km_parser_out_t *out);

/* True when the parser holds no byte: km_parser_poll*() would return 0 at any time. */
static inline bool km_parser_empty(const km_parser_t *p)
{
    return p->fill == 0u;
}

/* Frame-end tracker for the receive interrupt (docs/benchmarks.md "Per
 * byte"): follows the parser's framing a byte at a time (F9, FF|F5, ID,
 * length, then `length` more bytes) so that the main loop runs the parser
 * only when a frame may have ended, not on every byte. It never misses a
 * frame end the parser would find: where the parser's state leaves the
 * simple framing (a bad length, a gap inside a frame, a lost byte, bytes
 * left after a failed frame) it asks for the main loop on every byte until
 * km_rx_track_sync() re-aligns it with the parser. */
enum {
    KM_TRACK_HUNT = 0u,     /* waiting for an F9 */
    KM_TRACK_F9 = 1u,       /* F9 seen */
    KM_TRACK_COMMAND = 2u,  /* F9 FF seen */
    KM_TRACK_RESPONSE = 3u, /* F9 F5 seen */
    KM_TRACK_ID = 4u,       /* the ID seen: the length comes next */
    KM_TRACK_COUNT = 5u,    /* counting `left` bytes to the frame's end */
    KM_TRACK_EVERY = 6u,    /* out of step with the parser: wake on every byte */
};

typedef struct {
    uint32_t last_tick; /* tick of the newest byte */
    uint32_t gap_ticks; /* the parser's inter-byte gap */
    uint16_t left;      /* KM_TRACK_COUNT: bytes to the frame's end */
    uint8_t state;      /* KM_TRACK_* */
} km_rx_track_t;

/* Re-aligns the tracker with the parser once every received byte has been
 * fed to it (the receive interrupt masked). */
void km_rx_track_sync(km_rx_track_t *t, const km_parser_t *p);

/* The state after F9 (KM_TRACK_F9) and `byte`: the parser drops the F9
 * and judges this byte alone unless it is FF or F5. */
static inline __attribute__((always_inline)) unsigned km_rx_track_after_f9(uint8_t byte)
{
    return byte == KM_HDR1_COMMAND    ? KM_TRACK_COMMAND
           : byte == KM_HDR1_RESPONSE ? KM_TRACK_RESPONSE
           : byte == KM_HDR0          ? KM_TRACK_F9
                                      : KM_TRACK_HUNT;
}

/* The state after F9 FF|F5 (`state`) and the ID `byte`. A bad ID is never
 * F9 (249 is a valid ID of both kinds), so the parser's rescan of FF|F5
 * and the ID finds nothing. The test of km_id_is_addressable() written out:
 * a call could land outside the interrupt's RAM code (LTO outlines it). */
static inline __attribute__((always_inline)) unsigned km_rx_track_after_hdr1(unsigned state, uint8_t byte)
{
    const bool id_ok =
        byte <= KM_ID_MAX || (state == KM_TRACK_COMMAND && (byte == KM_ID_SUPER || byte == KM_ID_BROADCAST));
    return id_ok ? KM_TRACK_ID : KM_TRACK_HUNT;
}

/* km_rx_track_byte() for a byte on time and after no loss, in any state but
 * counting. Ranges of states, not a chain of equalities: GCC turns such a
 * chain into a table walked by a libgcc helper, which is in flash. */
static inline __attribute__((always_inline)) bool km_rx_track_header(km_rx_track_t *t, unsigned state,
                                                                     uint8_t byte)
{
    if (state <= KM_TRACK_RESPONSE) {
        if (state == KM_TRACK_F9) {
            t->state = (uint8_t)km_rx_track_after_f9(byte);
        } else if (state != KM_TRACK_HUNT) { /* COMMAND or RESPONSE */
            t->state = (uint8_t)km_rx_track_after_hdr1(state, byte);
        } else if (byte == KM_HDR0) {
            t->state = KM_TRACK_F9;
        }
        return false; /* hunting, the parser keeps nothing but an F9 */
    }
    if (state != KM_TRACK_ID) {
        return true; /* KM_TRACK_EVERY */
    }
    if ((uint32_t)byte - KM_LENGTH_MIN > KM_LENGTH_MAX - KM_LENGTH_MIN) {
        t->state = KM_TRACK_EVERY; /* the rescan may find an F9 in the ID */
        return true;
    }
    t->left = byte;
    t->state = KM_TRACK_COUNT;
    return false;
}

/* The parser's framing rule for one received byte; true when the parser
 * must look: a frame may be complete, 64 bytes of a long frame are waiting
 * (the queue holds 128), or the tracker lost step. Inline: it runs in the
 * receive interrupt (in RAM on the stm32g031, so that a flash erase does
 * not stall it); a byte inside a frame takes the first branches. */
static inline __attribute__((always_inline)) bool km_rx_track_byte(km_rx_track_t *t, uint8_t byte,
                                                                   uint32_t tick, bool lost)
{
    const uint32_t since = tick - t->last_tick;
    t->last_tick = tick;
    const unsigned state = t->state;
    if (since <= t->gap_ticks && !lost) {
        if (state == KM_TRACK_COUNT) {
            const uint32_t left = (uint32_t)t->left - 1u;
            t->left = (uint16_t)left;
            if ((left & 63u) != 0u) {
                return false;
            }
            if (left == 0u) {
                t->state = KM_TRACK_HUNT;
            }
            return true;
        }
        return km_rx_track_header(t, state, byte);
    }
    if (state == KM_TRACK_HUNT && (byte != KM_HDR0 || !lost)) {
        if (byte == KM_HDR0) {
            t->state = KM_TRACK_F9; /* an idle bus: the gap does not matter */
        }
        return lost;
    }
    t->state = KM_TRACK_EVERY; /* a cut: the parser may rescan */
    return true;
}

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
