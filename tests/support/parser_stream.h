/* SPDX-License-Identifier: Apache-2.0 */
/* Seeded byte streams for the parser's differential tests (test_parser_batch,
 * test_parser_track): good and corrupted command frames, other servos'
 * responses (docs/protocol.md §2), truncated frames, bad headers, noise with
 * F9 and F9 FF in it, ticks that stand still, step or jump past the gap (§7),
 * and lost bytes. Header-only, as parser_rig.h. */
#ifndef PARSER_STREAM_H
#define PARSER_STREAM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "parser_rig.h"

#define PS_CAP (200000u + 512u) /* the longest stream, and a piece past it */

typedef struct {
    uint8_t bytes[PS_CAP];
    uint32_t ticks[PS_CAP];
    uint8_t lost[PS_CAP]; /* 1: a byte lost (an overrun) before this one */
    uint8_t last[PS_CAP]; /* 1: the last byte of a whole, good frame */
    size_t len;
    uint32_t rng;
} ps_stream_t;

/* The next number of the stream's xorshift32 generator. */
static inline uint32_t ps_rnd(ps_stream_t *s)
{
    s->rng ^= s->rng << 13;
    s->rng ^= s->rng >> 17;
    s->rng ^= s->rng << 5;
    return s->rng;
}

/* Appends one byte. */
static inline void ps_put(ps_stream_t *s, uint8_t b)
{
    s->bytes[s->len] = b;
    s->last[s->len] = 0u;
    s->len++;
}

/* Appends a frame (command FF or response F5) with a random body; broken on request. */
static inline void ps_put_frame(ps_stream_t *s, uint8_t hdr1, uint8_t id, size_t body_len, bool corrupt,
                                bool truncate)
{
    uint8_t f[KM_FRAME_MAX];
    uint8_t body[KM_BODY_MAX];
    for (size_t i = 0; i < body_len; i++) {
        body[i] = (ps_rnd(s) % 16u == 0u) ? (uint8_t)((i & 1u) ? 0xFFu : 0xF9u) : (uint8_t)ps_rnd(s);
    }
    size_t n = rig_command(f, id, (uint8_t)ps_rnd(s), body, body_len);
    f[1] = hdr1;
    if (corrupt) {
        f[n - 1u] = (uint8_t)(f[n - 1u] ^ (1u + ps_rnd(s) % 255u));
    }
    if (truncate) {
        n = 1u + ps_rnd(s) % (n - 1u);
    }
    for (size_t i = 0; i < n; i++) {
        ps_put(s, f[i]);
    }
    s->last[s->len - 1u] = (uint8_t)(!corrupt && !truncate);
}

/* An ID of any kind: mostly 0..12, now and then super, broadcast or any byte. */
static inline uint8_t ps_any_id(ps_stream_t *s)
{
    const uint32_t r = ps_rnd(s) % 16u;
    return r == 0u ? 0xFDu : r == 1u ? 0xFEu : r == 2u ? (uint8_t)ps_rnd(s) : (uint8_t)(r - 3u);
}

/* Appends one piece of a rough stream: a frame of any kind, broken or not, or noise. */
static inline void ps_put_piece(ps_stream_t *s, uint32_t kind, size_t body_len)
{
    if (kind <= 2u) {
        ps_put_frame(s, 0xFF, ps_any_id(s), body_len, false, false);
    } else if (kind == 3u) {
        ps_put_frame(s, 0xF5, (uint8_t)(ps_rnd(s) % 12u), body_len, false, false);
    } else if (kind <= 5u) {
        ps_put_frame(s, kind == 4u ? 0xFFu : 0xF5u, ps_any_id(s), body_len, true, false);
    } else if (kind == 6u) {
        ps_put_frame(s, ps_rnd(s) % 2u ? 0xFFu : 0xF5u, ps_any_id(s), body_len, false, true);
    } else if (kind == 7u) { /* a bad length or ID after a real header */
        ps_put(s, 0xF9);
        ps_put(s, ps_rnd(s) % 2u ? 0xFFu : 0xF5u);
        ps_put(s, ps_rnd(s) % 2u ? (uint8_t)(251u + ps_rnd(s) % 5u) : 1u);
        ps_put(s, (uint8_t)(ps_rnd(s) % 2u ? ps_rnd(s) % 2u : 253u + ps_rnd(s) % 3u));
    } else { /* noise, F9 and F9 FF in it */
        for (uint32_t i = 1u + ps_rnd(s) % 6u; i > 0u; i--) {
            const uint32_t r = ps_rnd(s) % 8u;
            ps_put(s, r == 0u ? 0xF9u : r == 1u ? 0xFFu : (uint8_t)ps_rnd(s));
        }
    }
}

/* Fills s with at least `len` bytes from `seed`, then ticks (`gap` the parser's
 * gap) and lost bytes; `clean`: whole good frames only, one tick apart, none lost. */
static inline void ps_make(ps_stream_t *s, uint32_t seed, size_t len, uint32_t gap, bool clean)
{
    s->rng = seed;
    s->len = 0;
    while (s->len < len) {
        const uint32_t kind = clean ? ps_rnd(s) % 4u : ps_rnd(s) % 10u;
        const size_t body_len = (ps_rnd(s) % 8u == 0u) ? ps_rnd(s) % (KM_BODY_MAX + 1u) : ps_rnd(s) % 12u;
        if (clean && kind <= 2u) {
            ps_put_frame(s, 0xFF, (uint8_t)(ps_rnd(s) % 251u), body_len, false, false);
        } else {
            ps_put_piece(s, kind, body_len);
        }
    }
    uint32_t t = ps_rnd(s); /* anywhere, so the 32-bit wrap is crossed at times */
    for (size_t i = 0; i < s->len; i++) {
        const uint32_t r = ps_rnd(s) % 64u;
        t += clean ? 1u : r == 0u ? gap + 1u + ps_rnd(s) % 20u : r == 1u ? gap : r < 8u ? 0u : 1u;
        s->ticks[i] = t;
        s->lost[i] = !clean && ps_rnd(s) % 997u == 0u;
    }
}

#endif
