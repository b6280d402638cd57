/* SPDX-License-Identifier: Apache-2.0 */
/* Frame parser tests, part 3: a seeded, deterministic property test.
 *
 * A stream mixes random good command frames with random garbage, valid and
 * corrupted response frames, corrupted and truncated command frames, and
 * bad headers. To keep the property honest, every byte of the bad pieces
 * after their own F9 is drawn from values other than F9, so no bad piece can
 * start a candidate that swallows a following good frame by luck; good
 * frames and valid responses carry any byte (F9 FF in bodies included).
 * A truncated frame is followed by a gap longer than gap_ticks.
 * Property: every good frame is delivered exactly once, in order, with its
 * fields intact, and each counter equals the number of pieces of its kind
 * (docs/protocol.md §2 frames and responses, §7 gap). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "parser_rig.h"

#define GAP 8u
#define PIECES 1000u /* ~400 good frames: fits the rig */

static uint32_t s_rng;

static uint32_t rnd(void) /* xorshift32 */
{
    s_rng ^= s_rng << 13;
    s_rng ^= s_rng >> 17;
    s_rng ^= s_rng << 5;
    return s_rng;
}

static uint8_t rnd_byte(void)
{
    return (uint8_t)(rnd() >> 24);
}

static uint8_t rnd_not_f9(void)
{
    uint8_t b;
    do {
        b = rnd_byte();
    } while (b == 0xF9u);
    return b;
}

static uint8_t rnd_id(void)
{
    uint8_t id;
    do {
        id = rnd_byte();
    } while (!km_id_is_addressable(id));
    return id;
}

typedef struct {
    rig_t rig;
    km_frame_t want[PIECES];
    unsigned n_want, n_resp, n_csum, n_csum_cmd, n_trunc, n_framing;
} world_t;

/* Feeds bytes with random steps inside the gap, sometimes polling between. */
static void send(world_t *w, const uint8_t *b, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        rig_feed(&w->rig, &b[i], 1u, 0u);
        w->rig.tick += rnd() % (GAP + 1u);
        if ((rnd() & 15u) == 0u) {
            rig_poll(&w->rig, w->rig.tick); /* within the gap: must change nothing */
        }
    }
}

static void piece_good(world_t *w)
{
    uint8_t body[KM_BODY_MAX];
    uint8_t buf[KM_FRAME_MAX];
    const size_t len = (rnd() & 3u) ? rnd() % 12u : rnd() % (KM_BODY_MAX + 1u);
    for (size_t i = 0; i < len; i++) {
        body[i] = (rnd() & 7u) ? rnd_byte() : ((i & 1u) ? 0xFFu : 0xF9u);
    }
    km_frame_t *f = &w->want[w->n_want++];
    f->id = rnd_id();
    f->cmd = rnd_byte();
    f->body_len = (uint8_t)len;
    memcpy(f->body, body, len);
    send(w, buf, rig_command(buf, f->id, f->cmd, body, len));
}

static void piece_response(world_t *w, bool corrupt)
{
    uint8_t body[64];
    uint8_t buf[80];
    const size_t len = rnd() % sizeof body;
    for (size_t i = 0; i < len; i++) {
        body[i] = corrupt ? rnd_not_f9() : ((rnd() & 3u) ? rnd_byte() : 0xF9u);
    }
    size_t n;
    do {
        n = rig_command(buf, (uint8_t)(rnd() % (KM_ID_MAX + 1u)), corrupt ? rnd_not_f9() : rnd_byte(), body,
                        len);
        buf[1] = 0xF5;
        buf[n - 1u] = km_checksum(&buf[2], (uint32_t)(n - 3u));
        if (corrupt) {
            buf[n - 1u] = (uint8_t)(buf[n - 1u] + 1u + rnd() % 255u);
        }
    } while (corrupt && (buf[2] == 0xF9u || buf[n - 1u] == 0xF9u));
    if (corrupt) {
        w->n_csum++;
    } else {
        w->n_resp++;
    }
    send(w, buf, n);
}

/* A whole command frame with a wrong checksum, no F9 after its header. */
static void piece_bad_checksum(world_t *w)
{
    uint8_t buf[40];
    size_t n = 6u + rnd() % 30u;
    buf[0] = 0xF9;
    buf[1] = 0xFF;
    do {
        buf[2] = rnd_id();
    } while (buf[2] == 0xF9u);
    buf[3] = (uint8_t)(n - 4u);
    for (size_t i = 4; i < n - 1u; i++) {
        buf[i] = rnd_not_f9();
    }
    const uint8_t good = km_checksum(&buf[2], (uint32_t)(n - 3u));
    do {
        buf[n - 1u] = rnd_not_f9();
    } while (buf[n - 1u] == good);
    w->n_csum++;
    w->n_csum_cmd++;
    send(w, buf, n);
}

/* A command frame cut short, then silence longer than the gap. */
static void piece_truncated(world_t *w)
{
    uint8_t buf[KM_FRAME_MAX];
    uint8_t body[KM_BODY_MAX];
    const size_t len = 1u + rnd() % 40u;
    for (size_t i = 0; i < len; i++) {
        body[i] = rnd_not_f9();
    }
    uint8_t id;
    do {
        id = rnd_id();
    } while (id == 0xF9u);
    const size_t n = rig_command(buf, id, rnd_not_f9(), body, len);
    send(w, buf, 1u + rnd() % (n - 1u)); /* 1 .. n-1 bytes */
    w->rig.tick += GAP + 1u + rnd() % 100u;
    w->n_trunc++;
}

/* A proper F9 FF / F9 F5 header with a bad ID or a bad length. */
static void piece_bad_header(world_t *w)
{
    static const uint8_t bad_ids[] = {251, 252, 255};
    static const uint8_t bad_lens[] = {0, 1, 253, 254, 255};
    uint8_t buf[8] = {0xF9, (rnd() & 1u) ? 0xFFu : 0xF5u};
    size_t n;
    if (rnd() & 1u) {
        buf[2] = bad_ids[rnd() % 3u];
        n = 3;
    } else {
        buf[2] = (uint8_t)(rnd() % (KM_ID_MAX + 1u));
        while (buf[2] == 0xF9u) {
            buf[2] = (uint8_t)(rnd() % (KM_ID_MAX + 1u));
        }
        buf[3] = bad_lens[rnd() % 5u];
        n = 4;
    }
    w->n_framing++;
    send(w, buf, n);
}

static void piece_garbage(world_t *w)
{
    uint8_t buf[24];
    const size_t n = 1u + rnd() % sizeof buf;
    for (size_t i = 0; i < n; i++) {
        buf[i] = rnd_not_f9();
    }
    send(w, buf, n);
}

static void run_world(uint32_t seed)
{
    static world_t w;
    memset(&w, 0, sizeof w);
    s_rng = seed;
    rig_init(&w.rig, GAP, rnd()); /* any start tick, wrap-around included */
    for (unsigned i = 0; i < PIECES; i++) {
        switch (rnd() % 10u) {
        case 0:
        case 1:
        case 2:
        case 3:
            piece_good(&w);
            break;
        case 4:
            piece_response(&w, false);
            break;
        case 5:
            piece_response(&w, true);
            break;
        case 6:
            piece_bad_checksum(&w);
            break;
        case 7:
            piece_truncated(&w);
            break;
        case 8:
            piece_bad_header(&w);
            break;
        default:
            piece_garbage(&w);
            break;
        }
    }
    rig_poll(&w.rig, w.rig.tick + GAP + 1u);
    /* Every kind of piece really occurred. */
    assert_true(w.n_want > 300u && w.n_resp > 0u && w.n_csum_cmd > 0u && w.n_trunc > 0u && w.n_framing > 0u &&
                w.n_csum > w.n_csum_cmd);

    assert_int_equal(w.rig.n, w.n_want);
    for (unsigned i = 0; i < w.n_want; i++) {
        const km_frame_t *got = &w.rig.frames[i];
        assert_int_equal(got->id, w.want[i].id);
        assert_int_equal(got->cmd, w.want[i].cmd);
        assert_int_equal(got->body_len, w.want[i].body_len);
        assert_memory_equal(got->body, w.want[i].body, w.want[i].body_len);
    }
    const km_parser_stats_t *s = &w.rig.p.stats;
    assert_int_equal(s->frames_ok, w.n_want);
    assert_int_equal(s->responses_skipped, w.n_resp);
    assert_int_equal(s->checksum_errors, w.n_csum);
    assert_int_equal(w.rig.checksum_events, w.n_csum_cmd);
    assert_int_equal(s->timeouts, w.n_trunc);
    assert_int_equal(s->framing_errors, w.n_framing);
    assert_int_equal(w.rig.p.fill, 0);
}

/* §2, §7: the property over several fixed seeds. */
static void test_s2_s7_random_streams_deliver_every_good_frame(void **state)
{
    (void)state;
    static const uint32_t seeds[] = {1u, 0x2545F491u, 0xDEADBEEFu, 12345u, 0x9E3779B9u, 7u, 0xC0FFEEu, 99u};
    for (unsigned i = 0; i < sizeof seeds / sizeof seeds[0]; i++) {
        run_world(seeds[i]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s2_s7_random_streams_deliver_every_good_frame),
    };
    return cmocka_run_group_tests_name("parser_random", tests, NULL, NULL);
}
