/* SPDX-License-Identifier: Apache-2.0 */
/* The list scans of the multi-ID commands (protocol/km_cmd_multi.c): 0x82's
 * word-at-a-time search and 0x83's strided search find this servo's first
 * entry exactly as a byte-by-byte reading of docs/protocol.md §3 ("Multi-ID
 * write") and docs/protocol-decisions.md ("Multi-ID read 0x82") does, at
 * every list length, wherever the body lies in memory (the four word
 * alignments), with bytes around this servo's ID that differ from it in
 * one bit or by one, and with value bytes equal to its ID. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_dispatch.h"
#include "km_test_support.h"

static kt_fx_t fx;
/* The body, at buf + align: word-aligned storage. */
static uint32_t buf_words[(KM_BODY_MAX + 8u) / 4u];

static const uint8_t owns[] = {0u, 1u, 0x7Fu, 0x80u, KM_ID_MAX};

/* A byte that is not `own` but close to it: one bit or one count away. */
static uint8_t prv_near(uint8_t own, unsigned i)
{
    static const uint8_t flip[] = {0x80u, 0x01u, 0x7Fu, 0xFFu, 0x10u};
    const uint8_t v = (uint8_t)(i % 3u == 0u ? own ^ flip[i % 5u] : own + (i % 2u ? 1u : 0xFFu));
    return v;
}

/* Hands the servo a broadcast frame whose body lies at buf + align. */
static void prv_handle(uint8_t cmd, unsigned align, const uint8_t *body, unsigned n)
{
    uint8_t *const at = (uint8_t *)buf_words + align;
    memcpy(at, body, n);
    const km_frame_view_t view = {.id = KM_ID_BROADCAST, .cmd = cmd, .body_len = (uint8_t)n, .body = at};
    memset(&fx.reply, 0xA5, sizeof fx.reply);
    km_servo_handle_view(&fx.s, &view, &fx.reply);
}

/* 0x82 of 0x46 with `own` first at position j (n = absent) in a list of n,
 * listed again after j: the delay of the answer, or -1 for none. */
static long prv_mread(uint8_t own, unsigned align, unsigned n, unsigned j)
{
    uint8_t body[KM_BODY_MAX];
    body[0] = 0x46u;
    for (unsigned i = 0; i < n; i++) {
        body[1u + i] = i == j || (j < n && i == n - 1u) ? own : prv_near(own, i);
    }
    kt_init(&fx, kt_product_pot(), own);
    prv_handle(0x82u, align, body, 1u + n);
    return fx.reply.len > 0u ? (long)fx.reply.delay_us : -1;
}

/* "Multi-ID read 0x82": the answer's slot is the first listed position, at
 * every length up to the frame's limit and every alignment. */
static void test_mread_scan_every_length_and_alignment(void **state)
{
    (void)state;
    for (unsigned o = 0; o < sizeof owns; o++) {
        const uint8_t own = owns[o];
        const long d0 = prv_mread(own, 0u, 2u, 0u);
        const long slot = prv_mread(own, 0u, 2u, 1u) - d0;
        assert_true(d0 > 0 && slot > 0);
        for (unsigned align = 0; align < 4u; align++) {
            for (unsigned n = 1; n <= KM_BODY_MAX - 1u; n++) {
                assert_int_equal(prv_mread(own, align, n, n), -1);
                const unsigned js[] = {0u, n - 1u, n / 2u, (n * 5u) / 8u, n > 8u ? n - 8u : 0u};
                for (unsigned k = 0; k < sizeof js / sizeof js[0]; k++) {
                    assert_int_equal(prv_mread(own, align, n, js[k]), d0 + (long)js[k] * slot);
                }
            }
        }
    }
}

/* 0x83 of addr with entries of 1 + k bytes, `own` first in entry j (n =
 * absent) and again after it with another value; the value bytes of the
 * other entries equal `own`. The requests the servo made. */
static unsigned prv_mwrite(uint8_t own, unsigned align, uint8_t addr, uint8_t k, unsigned n, unsigned j)
{
    uint8_t body[KM_BODY_MAX];
    body[0] = addr;
    body[1] = k;
    for (unsigned e = 0; e < n; e++) {
        uint8_t *const entry = &body[2u + e * (1u + k)];
        const bool listed = e == j || (j < n && e == n - 1u);
        entry[0] = listed ? own : prv_near(own, e);
        for (unsigned b = 1; b <= k; b++) {
            entry[b] = own; /* never mistaken for an ID */
        }
        if (listed) {
            /* the first listed entry 1 (0x64) or 100, a later one 2 or 200 */
            entry[1] = k == 1u ? (e == j ? 1u : 2u) : (e == j ? 100u : 200u);
            if (k >= 2u) {
                entry[2] = 0u;
            }
            if (k == 4u) { /* 0x65's time: 1,000 ms */
                entry[3] = 0xE8u;
                entry[4] = 0x03u;
            }
        }
    }
    kt_init(&fx, kt_product_pot(), own);
    prv_handle(0x83u, align, body, 2u + n * (1u + k));
    kt_no_reply(&fx);
    return fx.fake.n_requests;
}

/* "Multi-ID write": a listed servo runs its first entry, an unlisted one
 * nothing, for each entry size 0x83 takes (1, 2, 4 bytes), at every list
 * length up to the frame's limit and every alignment. */
static void test_mwrite_scan_every_length_and_alignment(void **state)
{
    (void)state;
    static const struct {
        uint8_t addr;
        uint8_t k;
    } regs[] = {{0x64u, 1u}, {0x68u, 2u}, {0x65u, 4u}};
    for (unsigned o = 0; o < sizeof owns; o++) {
        const uint8_t own = owns[o];
        for (unsigned r = 0; r < 3u; r++) {
            const uint8_t k = regs[r].k;
            const unsigned max = (KM_BODY_MAX - 2u) / (1u + k);
            for (unsigned align = 0; align < 4u; align++) {
                for (unsigned n = 1; n <= max; n++) {
                    assert_int_equal(prv_mwrite(own, align, regs[r].addr, k, n, n), 0u);
                    const unsigned js[] = {0u, n - 1u, n / 2u, n > 5u ? n - 5u : 0u};
                    for (unsigned i = 0; i < sizeof js / sizeof js[0]; i++) {
                        assert_int_equal(prv_mwrite(own, align, regs[r].addr, k, n, js[i]), 1u);
                        if (k == 1u) {
                            assert_int_equal(fx.fake.requests[0].u.torque, 1u);
                        } else {
                            assert_int_equal(fx.fake.requests[0].u.move.target, 100);
                        }
                    }
                }
            }
        }
    }
}

/* A byte for a random list: this servo's ID now and then, else one close
 * to it (one bit or one count away), 0, 0xFF or any. */
static uint8_t prv_pick(uint32_t *seed, uint8_t own, unsigned own_in_16)
{
    *seed = *seed * 1103515245u + 12345u;
    const uint32_t r = *seed >> 16;
    if (r % 16u < own_in_16) {
        return own;
    }
    switch ((r >> 4) % 6u) {
    case 0:
        return (uint8_t)(own ^ 0x80u);
    case 1:
        return (uint8_t)(own ^ 0x01u);
    case 2:
        return (uint8_t)(own + 1u);
    case 3:
        return 0u;
    case 4:
        return 0xFFu;
    default:
        return (uint8_t)(r >> 8);
    }
}

/* The first entry of `own` read byte by byte (§3), or n: what the scans
 * must find. */
static unsigned prv_first_entry(const uint8_t *ids, unsigned n, unsigned stride, uint8_t own)
{
    unsigned j = 0;
    while (j < n && ids[j * stride] != own) {
        j++;
    }
    return j;
}

/* "Multi-ID write" and "Multi-ID read 0x82" on random lists (fixed seed):
 * IDs near this servo's, value bytes equal to it, 0 or 0xFF (a zero byte
 * next to a match, a borrow across an entry), any length and alignment;
 * the entry that runs, or the answer's slot, is the first listed one read
 * byte by byte, and a value byte never counts as an ID. */
static void test_scan_random_lists_as_read_byte_by_byte(void **state)
{
    (void)state;
    static const struct {
        uint8_t addr;
        uint8_t k;
    } regs[] = {{0x46u, 0u}, {0x64u, 1u}, {0x68u, 2u}, {0x65u, 4u}};
    uint32_t seed = 0x5EEDu;
    uint8_t body[KM_BODY_MAX];
    for (unsigned round = 0; round < 6000u; round++) {
        const uint8_t own = owns[round % sizeof owns];
        const unsigned r = (round / sizeof owns) % 4u;
        const unsigned stride = 1u + regs[r].k;
        const unsigned head = regs[r].k ? 2u : 1u;
        const unsigned max = (KM_BODY_MAX - head) / stride;
        const unsigned n = 1u + (unsigned)(prv_pick(&seed, 0u, 0u) * 7u + round) % max;
        const unsigned align = (round / 7u) % 4u;
        const unsigned own_in_16 = round % 3u; /* 0: never listed */
        body[0] = regs[r].addr;
        body[1] = regs[r].k;
        for (unsigned i = 0; i < n * stride; i++) {
            body[head + i] = prv_pick(&seed, own, i % stride == 0u ? own_in_16 : 4u);
        }
        const unsigned j = prv_first_entry(&body[head], n, stride, own);
        if (regs[r].k == 0u) {
            const long d0 = prv_mread(own, 0u, 2u, 0u);
            const long slot = prv_mread(own, 0u, 2u, 1u) - d0;
            kt_init(&fx, kt_product_pot(), own);
            prv_handle(0x82u, align, body, head + n);
            assert_int_equal(fx.reply.len > 0u ? (long)fx.reply.delay_us : -1,
                             j < n ? d0 + (long)j * slot : -1);
            continue;
        }
        for (unsigned e = j; e < n; e++) { /* the value the first listed entry writes, another after it */
            uint8_t *const value = &body[head + e * stride + 1u];
            if (body[head + e * stride] == own) {
                memset(value, 0, regs[r].k);
                value[0] = regs[r].k == 1u ? (e == j ? 1u : 2u) : (e == j ? 100u : 200u);
                if (regs[r].k == 4u) { /* 0x65's time: 1,000 ms */
                    value[2] = 0xE8u;
                    value[3] = 0x03u;
                }
            }
        }
        kt_init(&fx, kt_product_pot(), own);
        prv_handle(0x83u, align, body, head + n * stride);
        assert_int_equal(fx.fake.n_requests, j < n ? 1u : 0u);
        if (j < n && regs[r].k == 1u) {
            assert_int_equal(fx.fake.requests[0].u.torque, 1u);
        } else if (j < n) {
            assert_int_equal(fx.fake.requests[0].u.move.target, 100);
        }
    }
}

/* "Multi-ID write": parameters that are not whole entries (a length that
 * is not a multiple of 1 + k) fail on every servo and run nothing; the
 * test of whole entries takes no division, so every length is tried. */
static void test_mwrite_whole_entries_every_length(void **state)
{
    (void)state;
    static const struct {
        uint8_t addr;
        uint8_t k;
    } regs[] = {{0x64u, 1u}, {0x68u, 2u}, {0x65u, 4u}};
    uint8_t body[KM_BODY_MAX];
    for (unsigned r = 0; r < 3u; r++) {
        for (unsigned n_params = 1; n_params <= KM_BODY_MAX - 2u; n_params++) {
            body[0] = regs[r].addr;
            body[1] = regs[r].k;
            memset(&body[2], 0x33, n_params); /* listed nowhere: ID 0x33 is another servo */
            kt_init(&fx, kt_product_pot(), 1u);
            prv_handle(0x83u, n_params % 4u, body, 2u + n_params);
            const bool whole = n_params % (1u + regs[r].k) == 0u;
            assert_int_equal(fx.fake.n_requests, 0u);
            assert_int_equal(km_servo_status(&fx.s), whole ? 0 : KM_ST_FAILED);
        }
    }
}

/* The answer slot (docs/protocol-decisions.md "Multi-ID read 0x82"; the
 * super ID's slots too) is the answer's bits plus two bytes' at the baud,
 * rounded up: computed without a division, it is the exact ceiling at
 * every answer length and every baud a servo may run at. */
static void test_slot_length_every_answer_and_baud(void **state)
{
    (void)state;
    static const uint32_t bauds[] = {300u,     1200u,    9600u,    19200u,   38400u,    57600u,
                                     76800u,   100000u,  115200u,  128000u,  230400u,   250000u,
                                     460800u,  500000u,  921600u,  1000000u, 1048577u,  1500000u,
                                     2000000u, 3000000u, 4000000u, 6553500u, 12345679u, 99999u};
    kt_init(&fx, kt_product_pot(), 1u);
    for (unsigned i = 0; i < sizeof bauds / sizeof bauds[0]; i++) {
        km_servo_set_active_baud(&fx.s, bauds[i]);
        for (uint16_t bytes = 0; bytes <= KM_FRAME_MAX; bytes++) {
            const uint64_t bits = ((uint64_t)bytes + 2u) * 10u;
            const uint64_t want = (bits * 1000000u + bauds[i] - 1u) / bauds[i];
            /* the super ID's answer: slot = own ID (1) slots after the delay */
            const uint32_t slot =
                km_dispatch_delay_us(&fx.s, KM_ID_SUPER, bytes) - km_dispatch_delay_us(&fx.s, 0u, bytes);
            assert_int_equal(slot, want);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mread_scan_every_length_and_alignment),
        cmocka_unit_test(test_mwrite_scan_every_length_and_alignment),
        cmocka_unit_test(test_mwrite_whole_entries_every_length),
        cmocka_unit_test(test_scan_random_lists_as_read_byte_by_byte),
        cmocka_unit_test(test_slot_length_every_answer_and_baud),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
