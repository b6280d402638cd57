/* SPDX-License-Identifier: Apache-2.0 */
/* Test rig for the frame parser: feeds byte strings with ticks, collects the
 * delivered frames and events, and builds command frames from parts. Shared
 * by the parser unit and property tests; header-only so each test stays one
 * executable. */
#ifndef PARSER_RIG_H
#define PARSER_RIG_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "km_parser.h"

#define RIG_MAX_FRAMES 512u

typedef struct {
    km_parser_t p;
    km_frame_t frames[RIG_MAX_FRAMES];
    unsigned n; /* frames delivered so far */
    unsigned checksum_events;
    uint32_t tick; /* tick of the next byte */
} rig_t;

static inline void rig_init(rig_t *r, uint32_t gap, uint32_t tick0)
{
    memset(r, 0, sizeof *r);
    km_parser_init(&r->p, gap);
    r->tick = tick0;
}

static inline void rig_take(rig_t *r, unsigned ev, const km_frame_t *f)
{
    if ((ev & KM_PARSE_FRAME) && r->n < RIG_MAX_FRAMES) {
        r->frames[r->n++] = *f;
    }
    if (ev & KM_PARSE_CHECKSUM_ERR) {
        r->checksum_events++;
    }
}

/* Feeds n bytes, `step` ticks apart, starting at r->tick; r->tick ends one
 * step after the last byte. Returns the tick of the last byte. */
static inline uint32_t rig_feed(rig_t *r, const uint8_t *b, size_t n, uint32_t step)
{
    uint32_t last = r->tick;
    for (size_t i = 0; i < n; i++) {
        km_frame_t f;
        memset(&f, 0xA5, sizeof f);
        last = r->tick;
        rig_take(r, km_parser_feed(&r->p, b[i], r->tick, &f), &f);
        r->tick += step;
    }
    return last;
}

/* Polls at `now` until the parser has nothing more to hand out. */
static inline void rig_poll(rig_t *r, uint32_t now)
{
    for (int guard = 0; guard < 300; guard++) {
        km_frame_t f;
        unsigned ev = km_parser_poll(&r->p, now, &f);
        rig_take(r, ev, &f);
        if (!(ev & KM_PARSE_FRAME)) {
            return;
        }
    }
}

/* Writes F9 FF id len cmd body.. checksum; returns the frame size. */
static inline size_t rig_command(uint8_t *out, uint8_t id, uint8_t cmd, const uint8_t *body, size_t body_len)
{
    out[0] = 0xF9;
    out[1] = 0xFF;
    out[2] = id;
    out[3] = (uint8_t)(body_len + 2u);
    out[4] = cmd;
    if (body_len) {
        memcpy(&out[5], body, body_len);
    }
    out[5 + body_len] = km_checksum(&out[2], (uint32_t)(3u + body_len));
    return 6u + body_len;
}

#endif
