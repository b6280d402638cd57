/* SPDX-License-Identifier: Apache-2.0 */
/* The bootloader's frame decoder (firmware/update/km_boot_rx.c,
 * docs/update.md §1) hands out exactly the frames the application's parser
 * (protocol/km_parser.c, docs/protocol.md §2, §7) does: the §2 worked frames,
 * a frame right after garbage, a response skipped whole, a gap cutting a
 * partial frame, and 20,000 random streams of good, corrupted and cut
 * frames, responses, noise and gaps compared frame by frame with the
 * parser (id, command, body and end tick), each byte followed by polls. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "km_boot_rx.h"
#include "km_parser.h"

#define GAP 10u

typedef struct {
    uint8_t id, cmd, len;
    uint8_t body[KM_BODY_MAX];
    uint32_t end;
} got_t;

static km_boot_rx_t s_rx;
static km_parser_t s_p;

static uint32_t s_seed = 1u;
static uint32_t prv_rand(void)
{
    s_seed = s_seed * 1103515245u + 12345u;
    return s_seed >> 8;
}

static unsigned prv_take_rx(bool ok, const km_frame_view_t *v, got_t *g, unsigned n)
{
    if (ok) {
        g[n] = (got_t){v->id, v->cmd, v->body_len, {0}, v->end_tick};
        memcpy(g[n].body, v->body, v->body_len);
        return n + 1u;
    }
    return n;
}

static unsigned prv_take_p(unsigned ev, const km_frame_t *f, got_t *g, unsigned n)
{
    if ((ev & KM_PARSE_FRAME) != 0u) {
        g[n] = (got_t){f->id, f->cmd, f->body_len, {0}, f->end_tick};
        memcpy(g[n].body, f->body, f->body_len);
        return n + 1u;
    }
    return n;
}

/* Feeds one byte to both at `now`, then polls both at `poll_at` until
 * neither hands out a frame; the frames must be the same, in order. */
static unsigned prv_step(uint8_t b, uint32_t now, uint32_t poll_at, got_t *out)
{
    static got_t a[64];
    static got_t p[64];
    static km_frame_t f;
    km_frame_view_t v;
    unsigned na = prv_take_rx(km_boot_rx_feed(&s_rx, b, now, &v), &v, a, 0u);
    unsigned np = prv_take_p(km_parser_feed(&s_p, b, now, &f), &f, p, 0u);
    for (unsigned k = 0; k < 60u; k++) {
        const unsigned na0 = na;
        const unsigned np0 = np;
        na = prv_take_rx(km_boot_rx_poll(&s_rx, poll_at, &v), &v, a, na);
        np = prv_take_p(km_parser_poll(&s_p, poll_at, &f), &f, p, np);
        if (na == na0 && np == np0) {
            break;
        }
    }
    assert_int_equal(na, np);
    for (unsigned i = 0; i < na; i++) {
        assert_int_equal(a[i].id, p[i].id);
        assert_int_equal(a[i].cmd, p[i].cmd);
        assert_int_equal(a[i].len, p[i].len);
        assert_memory_equal(a[i].body, p[i].body, a[i].len);
        assert_int_equal(a[i].end, p[i].end);
        if (out != NULL) {
            out[i] = a[i];
        }
    }
    return na;
}

static void prv_reset(void)
{
    km_boot_rx_init(&s_rx, GAP);
    km_parser_init(&s_p, GAP);
}

static unsigned prv_run(const uint8_t *bytes, unsigned n, got_t *out)
{
    unsigned got = 0u;
    for (unsigned i = 0; i < n; i++) {
        got += prv_step(bytes[i], i, i, out ? out + got : NULL);
    }
    return got;
}

/* docs/protocol.md §2 worked frames, back to back: each handed out once. */
static void test_worked_frames(void **state)
{
    (void)state;
    static const uint8_t k[] = {0xF9, 0xFF, 0x01, 0x02, 0x01, 0xFB,        /* ping 1 */
                                0xF9, 0xFF, 0x01, 0x03, 0x02, 0x0B, 0xEE,  /* read 0x0B */
                                0xF9, 0xFF, 0xFE, 0x03, 0x78, 0x05, 0x81}; /* VERIFY bcast */
    got_t g[4];
    prv_reset();
    assert_int_equal(prv_run(k, sizeof k, g), 3);
    assert_int_equal(g[0].cmd, 0x01);
    assert_int_equal(g[1].body[0], 0x0B);
    assert_int_equal(g[2].id, 0xFE);
    assert_int_equal(g[2].cmd, 0x78);
    assert_int_equal(g[2].body[0], 0x05);
}

/* A good frame inside a failed candidate's length is kept (rescan), a
 * response is skipped whole, a bad checksum hands out nothing. */
static void test_garbage_response_checksum(void **state)
{
    (void)state;
    static const uint8_t k[] = {0xF9, 0xFF, 0x01, 0x20,                   /* claims 36 bytes */
                                0xF9, 0xFF, 0x02, 0x02, 0x01, 0xFA,       /* ping 2 inside it */
                                0xF9, 0xF5, 0x01, 0x03, 0x00, 0x02, 0xF9, /* a response */
                                0xF9, 0xFF, 0x03, 0x02, 0x01, 0x00};      /* ping 3, bad sum */
    got_t g[4];
    prv_reset();
    /* Nothing while the first candidate waits for its 36 bytes ... */
    assert_int_equal(prv_run(k, sizeof k, g), 0);
    /* ... the gap fails it, and the rescan finds ping 2 and only that. */
    assert_int_equal(prv_step(0x00, sizeof k + GAP + 1u, sizeof k + GAP + 1u, g), 1);
    assert_int_equal(g[0].id, 2);
    assert_int_equal(g[0].end, sizeof k - 1u);
}

/* A silence longer than the gap in the middle of a frame drops it. */
static void test_gap_cuts(void **state)
{
    (void)state;
    static const uint8_t k[] = {0xF9, 0xFF, 0x01, 0x02, 0x01, 0xFB};
    prv_reset();
    unsigned got = 0u;
    for (unsigned i = 0; i < sizeof k; i++) {
        const uint32_t t = i < 3u ? i : i + GAP + 5u;
        got += prv_step(k[i], t, t, NULL);
    }
    assert_int_equal(got, 0);
}

static unsigned prv_frame(uint8_t *o, bool response)
{
    const uint8_t len = (uint8_t)(2u + prv_rand() % (prv_rand() % 8u == 0u ? 251u : 12u));
    o[0] = KM_HDR0;
    o[1] = response ? KM_HDR1_RESPONSE : KM_HDR1_COMMAND;
    o[2] = (uint8_t)(prv_rand() % 4u == 0u ? prv_rand() : prv_rand() % 4u);
    o[3] = len;
    for (unsigned i = 0; i + 2u < len; i++) {
        o[4u + i] = (uint8_t)(prv_rand() % 3u == 0u ? 0xF9u : prv_rand());
    }
    o[len + 3u] = km_checksum(o + 2, len + 1u);
    return len + 4u;
}

/* Random streams: the decoder and the parser hand out the same frames at
 * the same byte, with the same end tick. */
static void test_random_streams_match_the_parser(void **state)
{
    (void)state;
    static uint8_t s[4096];
    unsigned frames = 0u;
    unsigned bytes = 0u;
    for (unsigned run = 0; run < 20000u; run++) {
        s_seed = run + 1u;
        unsigned n = 0u;
        while (n < 600u) {
            const uint32_t kind = prv_rand() % 10u;
            if (kind < 5u || kind == 9u) {
                const unsigned len = prv_frame(s + n, kind == 9u);
                if (prv_rand() % 6u == 0u) {
                    s[n + prv_rand() % len] ^= (uint8_t)(1u + prv_rand() % 255u); /* corrupt */
                }
                n += prv_rand() % 8u == 0u ? prv_rand() % len : len; /* or cut short */
            } else {
                const unsigned k = 1u + prv_rand() % 6u;
                for (unsigned i = 0; i < k; i++) {
                    s[n++] = prv_rand() % 2u == 0u ? 0xF9u : (uint8_t)prv_rand();
                }
            }
        }
        prv_reset();
        uint32_t t = 0u;
        for (unsigned i = 0; i < n; i++) {
            t += prv_rand() % 40u == 0u ? GAP + 1u + prv_rand() % 5u : prv_rand() % 3u;
            const uint32_t poll_at = t + (prv_rand() % 30u == 0u ? GAP + 1u : 0u);
            frames += prv_step(s[i], t, poll_at, NULL);
            if (poll_at != t) {
                t = poll_at;
            }
        }
        bytes += n;
    }
    printf("boot_rx vs parser: %u bytes, %u frames handed out, all identical\n", bytes, frames);
    assert_true(frames > 20000u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_worked_frames),
        cmocka_unit_test(test_garbage_response_checksum),
        cmocka_unit_test(test_gap_cuts),
        cmocka_unit_test(test_random_streams_match_the_parser),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
