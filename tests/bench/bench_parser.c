/* SPDX-License-Identifier: Apache-2.0 */
/* Parser benchmark: feeds a realistic bus mix (docs/protocol.md §2: pings, reads,
 * writes, 0x83 multi-ID writes, 0x04/0x84 sync writes, other servos'
 * responses, occasional garbage) of about 100k bytes through
 * km_parser_feed (byte by byte) and again through km_parser_feed_bytes (in
 * runs of up to 64 bytes with their ticks, as the firmware's main loop feeds
 * it from the RX queue), and checks every generated command frame came out
 * both ways. Prints bytes fed and frames; exits 1 on a wrong count. Timing is measured from
 * outside (tools/bench/bench-parser runs it under callgrind), so the stream is
 * generated first and the feed loop does nothing else. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "km_parser.h"

#define STREAM_MAX 110000u
#define TARGET_BYTES 100000u

static uint8_t s_stream[STREAM_MAX];
static uint32_t s_len;
static uint32_t s_rng = 0x2545F491u;
static unsigned s_responses; /* response frames generated */

static uint32_t prv_rand(void) /* xorshift32: the same stream every run */
{
    s_rng ^= s_rng << 13;
    s_rng ^= s_rng >> 17;
    s_rng ^= s_rng << 5;
    return s_rng;
}

static void prv_frame(uint8_t hdr1, uint8_t id, uint8_t cmd, const uint8_t *body, uint8_t n)
{
    uint8_t *f = &s_stream[s_len];
    f[0] = 0xF9;
    f[1] = hdr1;
    f[2] = id;
    f[3] = (uint8_t)(n + 2u);
    f[4] = cmd;
    memcpy(&f[5], body, n);
    f[5u + n] = km_checksum(&f[2], 3u + (uint32_t)n);
    s_len += 6u + n;
    if (hdr1 == 0xF5u) {
        s_responses++;
    }
}

static uint8_t prv_id(void)
{
    return (uint8_t)(prv_rand() % 12u); /* a small bus */
}

/* Appends one bus exchange; returns the command frames it holds. */
static unsigned prv_exchange(void)
{
    uint8_t b[64];
    const uint8_t id = prv_id();
    switch (prv_rand() % 8u) {
    case 0: /* ping and its short answer */
        prv_frame(0xFF, id, 0x01, b, 0);
        b[0] = 0x00;
        prv_frame(0xF5, id, 0x00, b, 0);
        return 1;
    case 1: /* read position and its answer */
        b[0] = 0x46;
        prv_frame(0xFF, id, 0x02, b, 1);
        b[0] = 0x46;
        b[1] = (uint8_t)prv_rand();
        b[2] = 0xF9; /* answers may carry header bytes */
        prv_frame(0xF5, id, 0x02, b, 3);
        return 1;
    case 2: /* write 0x65: target, time */
        b[0] = 0x65;
        b[1] = (uint8_t)prv_rand();
        b[2] = (uint8_t)prv_rand();
        b[3] = 0xE8;
        b[4] = 0x03;
        prv_frame(0xFF, id, 0x03, b, 5);
        return 1;
    case 3: { /* 0x83 multi-ID 0x65 to k servos */
        const unsigned k = 2u + prv_rand() % 8u;
        b[0] = 0x65;
        b[1] = 4;
        for (unsigned i = 0; i < k; i++) {
            b[2 + 5 * i] = (uint8_t)i;
            b[3 + 5 * i] = (uint8_t)prv_rand();
            b[4 + 5 * i] = (uint8_t)prv_rand();
            b[5 + 5 * i] = 0xE8;
            b[6 + 5 * i] = 0x03;
        }
        prv_frame(0xFF, 0xFE, 0x83, b, (uint8_t)(2u + 5u * k));
        return 1;
    }
    case 4: { /* 0x04 sync writes to three servos, then 0x84 */
        for (uint8_t i = 1; i <= 3; i++) {
            b[0] = 0x65;
            b[1] = (uint8_t)prv_rand();
            b[2] = (uint8_t)prv_rand();
            b[3] = 0xE8;
            b[4] = 0x03;
            prv_frame(0xFF, i, 0x04, b, 5);
        }
        prv_frame(0xFF, 0xFE, 0x84, b, 0);
        return 4;
    }
    case 5: /* write torque on, short answer (response level 1) */
        b[0] = 0x64;
        b[1] = 0x02;
        prv_frame(0xFF, id, 0x03, b, 2);
        b[0] = 0x80;
        prv_frame(0xF5, id, 0x00, b, 0);
        return 1;
    case 6: /* read status */
        b[0] = 0x01;
        prv_frame(0xFF, id, 0x02, b, 1);
        b[0] = 0x01;
        b[1] = 0x00;
        b[2] = (uint8_t)prv_rand();
        prv_frame(0xF5, id, 0x02, b, 3);
        return 1;
    default: { /* line noise: a few bytes, never F9, so no frame is lost */
        const unsigned n = 1u + prv_rand() % 4u;
        for (unsigned i = 0; i < n; i++) {
            uint8_t g = (uint8_t)prv_rand();
            s_stream[s_len++] = (g == 0xF9u) ? 0x00u : g;
        }
        return 0;
    }
    }
}

int main(void)
{
    unsigned want = 0;
    while (s_len < TARGET_BYTES) {
        want += prv_exchange();
    }

    static km_parser_t p;
    static km_frame_t f;
    km_parser_init(&p, 10u);
    unsigned got = 0;
    uint32_t tick = 0;
    for (uint32_t i = 0; i < s_len; i++) {
        if (km_parser_feed(&p, s_stream[i], tick++, &f) & KM_PARSE_FRAME) {
            got++;
        }
    }

    /* The batch entry over the same bytes. */
    static uint32_t ticks[TARGET_BYTES + 1024u];
    for (uint32_t i = 0; i < s_len; i++) {
        ticks[i] = i;
    }
    static km_parser_t q;
    static km_parser_out_t out;
    km_parser_init(&q, 10u);
    unsigned got_batch = 0;
    for (uint32_t i = 0; i < s_len;) {
        const uint32_t n = s_len - i < 64u ? s_len - i : 64u;
        uint32_t used;
        if (km_parser_feed_bytes(&q, &s_stream[i], &ticks[i], n, &used, &out) & KM_PARSE_FRAME) {
            got_batch++;
        }
        i += used;
    }
    if (got_batch != want || q.stats.responses_skipped != s_responses) {
        fprintf(stderr, "bench_parser: batch entry delivered %u frames, generated %u\n", got_batch, want);
        return 1;
    }

    printf("bytes fed: %u\nframes: %u (expected %u)\nresponses skipped: %u (expected %u)\n"
           "sizeof(km_parser_t): %u\n",
           (unsigned)s_len, got, want, (unsigned)p.stats.responses_skipped, s_responses, (unsigned)sizeof p);
    if (got != want || p.stats.frames_ok != want || p.stats.responses_skipped != s_responses) {
        fprintf(stderr, "bench_parser: delivered %u frames, generated %u\n", got, want);
        return 1;
    }
    return 0;
}
