/* SPDX-License-Identifier: Apache-2.0 */
/* Frame parser tests, part 1: every command frame worked in docs/protocol.md §2
 * parses to the right id/cmd/body, alone and back to back, split at every
 * byte boundary, and the §1 ID rules. The bad-input catalog is in
 * test_parser_bad.c, the randomized property in test_parser_random.c. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "parser_rig.h"

#define GAP 10u

typedef struct {
    const char *name;
    uint8_t bytes[32];
    uint8_t size;
    uint8_t id;
    uint8_t cmd;
    uint8_t body[24];
    uint8_t body_len;
} worked_t;

/* Copied from the §2 table; the expected fields are read off by hand. */
static const worked_t s_worked[] = {
    {"ping ID 1", {0xF9, 0xFF, 0x01, 0x02, 0x01, 0xFB}, 6, 1, 0x01, {0}, 0},
    {"read protocol version", {0xF9, 0xFF, 0x01, 0x03, 0x02, 0x0B, 0xEE}, 7, 1, 0x02, {0x0B}, 1},
    {"read servo status", {0xF9, 0xFF, 0x01, 0x03, 0x02, 0x01, 0xF8}, 7, 1, 0x02, {0x01}, 1},
    {"write 0x65",
     {0xF9, 0xFF, 0x01, 0x07, 0x03, 0x65, 0x84, 0x03, 0xE8, 0x03, 0x1D},
     11,
     1,
     0x03,
     {0x65, 0x84, 0x03, 0xE8, 0x03},
     5},
    {"restart",
     {0xF9, 0xFF, 0x01, 0x07, 0x03, 0x02, 0xE1, 0xE2, 0xE3, 0xE4, 0x68},
     11,
     1,
     0x03,
     {0x02, 0xE1, 0xE2, 0xE3, 0xE4},
     5},
    {"multi-ID torque",
     {0xF9, 0xFF, 0xFE, 0x0A, 0x83, 0x64, 0x01, 0x01, 0x02, 0x02, 0x02, 0x03, 0x02, 0x03},
     14,
     0xFE,
     0x83,
     {0x64, 0x01, 0x01, 0x02, 0x02, 0x02, 0x03, 0x02},
     8},
    {"multi-ID 0x65",
     {0xF9, 0xFF, 0xFE, 0x13, 0x83, 0x65, 0x04, 0x05, 0x00, 0x00, 0xE8, 0x03,
      0x07, 0x5A, 0x00, 0xE8, 0x03, 0x09, 0xA6, 0xFF, 0xE8, 0x03, 0x2D},
     23,
     0xFE,
     0x83,
     {0x65, 0x04, 0x05, 0x00, 0x00, 0xE8, 0x03, 0x07, 0x5A, 0x00, 0xE8, 0x03, 0x09, 0xA6, 0xFF, 0xE8, 0x03},
     17},
    {"multi-ID 0x65 no time",
     {0xF9, 0xFF, 0xFE, 0x0D, 0x83, 0x65, 0x02, 0x05, 0x00, 0x00, 0x07, 0x5A, 0x00, 0x09, 0xA6, 0xFF, 0xF6},
     17,
     0xFE,
     0x83,
     {0x65, 0x02, 0x05, 0x00, 0x00, 0x07, 0x5A, 0x00, 0x09, 0xA6, 0xFF},
     11},
    {"sync torque ID 1", {0xF9, 0xFF, 0x01, 0x04, 0x04, 0x64, 0x02, 0x90}, 8, 1, 0x04, {0x64, 0x02}, 2},
    {"sync torque ID 2", {0xF9, 0xFF, 0x02, 0x04, 0x04, 0x64, 0x02, 0x8F}, 8, 2, 0x04, {0x64, 0x02}, 2},
    {"sync torque ID 3", {0xF9, 0xFF, 0x03, 0x04, 0x04, 0x64, 0x02, 0x8E}, 8, 3, 0x04, {0x64, 0x02}, 2},
    {"sync execute", {0xF9, 0xFF, 0xFE, 0x02, 0x84, 0x7B}, 6, 0xFE, 0x84, {0}, 0},
    {"sync 0x65 ID 5",
     {0xF9, 0xFF, 0x05, 0x07, 0x04, 0x65, 0x00, 0x00, 0xE8, 0x03, 0x9F},
     11,
     5,
     0x04,
     {0x65, 0x00, 0x00, 0xE8, 0x03},
     5},
    {"sync 0x65 ID 7",
     {0xF9, 0xFF, 0x07, 0x07, 0x04, 0x65, 0x5A, 0x00, 0xE8, 0x03, 0x43},
     11,
     7,
     0x04,
     {0x65, 0x5A, 0x00, 0xE8, 0x03},
     5},
    {"sync 0x65 ID 9",
     {0xF9, 0xFF, 0x09, 0x07, 0x04, 0x65, 0xA6, 0xFF, 0xE8, 0x03, 0xF6},
     11,
     9,
     0x04,
     {0x65, 0xA6, 0xFF, 0xE8, 0x03},
     5},
};
#define N_WORKED (sizeof s_worked / sizeof s_worked[0])

static void check_frame(const km_frame_t *f, const worked_t *w)
{
    print_message("  %s\n", w->name);
    assert_int_equal(f->id, w->id);
    assert_int_equal(f->cmd, w->cmd);
    assert_int_equal(f->body_len, w->body_len);
    if (w->body_len) {
        assert_memory_equal(f->body, w->body, w->body_len);
    }
}

/* §2: each worked frame alone; end_tick is the tick of its last byte. */
static void test_s2_worked_frames_each_alone(void **state)
{
    (void)state;
    for (unsigned i = 0; i < N_WORKED; i++) {
        rig_t r;
        rig_init(&r, GAP, 1000u);
        uint32_t last = rig_feed(&r, s_worked[i].bytes, s_worked[i].size, 3u);
        assert_int_equal(r.n, 1);
        check_frame(&r.frames[0], &s_worked[i]);
        assert_int_equal(r.frames[0].end_tick, last);
        assert_int_equal(r.p.stats.frames_ok, 1);
        assert_int_equal(r.p.stats.framing_errors + r.p.stats.checksum_errors, 0);
        assert_int_equal(r.p.fill, 0);
    }
}

/* §2: the frame is delivered on its last byte, not before. */
static void test_s2_frame_arrives_on_its_last_byte(void **state)
{
    (void)state;
    const worked_t *w = &s_worked[3];
    rig_t r;
    rig_init(&r, GAP, 0u);
    rig_feed(&r, w->bytes, (size_t)(w->size - 1u), 1u);
    assert_int_equal(r.n, 0);
    rig_feed(&r, &w->bytes[w->size - 1u], 1u, 1u);
    assert_int_equal(r.n, 1);
}

/* §2: all worked frames back to back, no gap, in one stream. */
static void test_s2_worked_frames_back_to_back(void **state)
{
    (void)state;
    rig_t r;
    rig_init(&r, GAP, 0u);
    for (unsigned round = 0; round < 3; round++) {
        for (unsigned i = 0; i < N_WORKED; i++) {
            rig_feed(&r, s_worked[i].bytes, s_worked[i].size, 0u);
        }
    }
    assert_int_equal(r.n, 3 * N_WORKED);
    for (unsigned i = 0; i < r.n; i++) {
        check_frame(&r.frames[i], &s_worked[i % N_WORKED]);
    }
}

/* §7: a frame split at every byte boundary, the halves exactly one gap apart,
 * is still one frame; one tick more and it is dropped as a timeout. */
static void test_s7_split_at_every_boundary(void **state)
{
    (void)state;
    const worked_t *w = &s_worked[6]; /* the longest: 23 bytes */
    for (unsigned cut = 1; cut < w->size; cut++) {
        for (uint32_t extra = 0; extra <= 1u; extra++) {
            rig_t r;
            rig_init(&r, GAP, 500u);
            rig_feed(&r, w->bytes, cut, 1u);
            r.tick += GAP - 1u + extra; /* last byte + GAP (+1) */
            rig_feed(&r, &w->bytes[cut], w->size - cut, 1u);
            if (extra == 0u) {
                assert_int_equal(r.n, 1);
                check_frame(&r.frames[0], w);
                assert_int_equal(r.p.stats.timeouts, 0);
            } else {
                assert_int_equal(r.n, 0);
                assert_int_equal(r.p.stats.timeouts, 1);
            }
        }
    }
}

/* §1: the parser delivers every addressable ID (0..250, 253, 254); the
 * dispatcher, not the parser, filters by ID. */
static void test_s1_every_addressable_id_delivered(void **state)
{
    (void)state;
    rig_t r;
    rig_init(&r, GAP, 0u);
    unsigned want = 0;
    for (unsigned id = 0; id <= 255u; id++) {
        uint8_t buf[8];
        const uint8_t body[1] = {(uint8_t)id};
        size_t n = rig_command(buf, (uint8_t)id, 0x02, body, 1);
        rig_feed(&r, buf, n, 1u);
        if (km_id_is_addressable((uint8_t)id)) {
            assert_int_equal(r.n, want + 1u);
            assert_int_equal(r.frames[want].id, id);
            want++;
        } else {
            assert_int_equal(r.n, want);
        }
    }
    assert_int_equal(want, 253);
    assert_int_equal(r.p.stats.framing_errors, 3); /* 251, 252, 255 */
}

/* §2: the longest frame (length 252, body 250 bytes) is delivered whole,
 * also when it wraps around the end of the parser's ring. */
static void test_s2_max_length_frame(void **state)
{
    (void)state;
    static uint8_t body[KM_BODY_MAX];
    static uint8_t buf[KM_FRAME_MAX];
    for (unsigned i = 0; i < KM_BODY_MAX; i++) {
        body[i] = (uint8_t)(i * 7u + 3u); /* includes F9 and FF bytes */
    }
    size_t n = rig_command(buf, 42, 0x03, body, KM_BODY_MAX);
    assert_int_equal(n, KM_FRAME_MAX);
    assert_int_equal(buf[3], KM_LENGTH_MAX);
    for (unsigned lead = 0; lead < 3; lead++) {
        rig_t r;
        rig_init(&r, GAP, 0u);
        for (unsigned k = 0; k < lead; k++) {
            rig_feed(&r, s_worked[3].bytes, s_worked[3].size, 1u); /* moves the ring head */
        }
        rig_feed(&r, buf, n, 1u);
        assert_int_equal(r.n, lead + 1u);
        const km_frame_t *f = &r.frames[lead];
        assert_int_equal(f->id, 42);
        assert_int_equal(f->cmd, 0x03);
        assert_int_equal(f->body_len, KM_BODY_MAX);
        assert_memory_equal(f->body, body, KM_BODY_MAX);
    }
}

/* §7: the default gap is 10 byte times, never under 1 ms. */
static void test_s7_default_gap(void **state)
{
    (void)state;
    assert_int_equal(km_parser_default_gap_us(9600), 10416);
    assert_int_equal(km_parser_default_gap_us(115200), 1000);
    assert_int_equal(km_parser_default_gap_us(1000000), 1000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s2_worked_frames_each_alone),
        cmocka_unit_test(test_s2_frame_arrives_on_its_last_byte),
        cmocka_unit_test(test_s2_worked_frames_back_to_back),
        cmocka_unit_test(test_s7_split_at_every_boundary),
        cmocka_unit_test(test_s1_every_addressable_id_delivered),
        cmocka_unit_test(test_s2_max_length_frame),
        cmocka_unit_test(test_s7_default_gap),
    };
    return cmocka_run_group_tests_name("parser", tests, NULL, NULL);
}
