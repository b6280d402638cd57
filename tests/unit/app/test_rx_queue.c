/* SPDX-License-Identifier: Apache-2.0 */
/* RX queue tests: order, ticks, full-queue loss marking, index wrap, and
 * the batch side (peek a run in place, release part of it). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_rx_queue.h"

static km_rx_queue_t s_q;

static void test_fifo_order_and_ticks(void **state)
{
    (void)state;
    km_rx_queue_init(&s_q);
    for (unsigned i = 0; i < 10; i++) {
        km_rx_queue_push(&s_q, (uint8_t)(0xF0u + i), 1000u + i, false);
    }
    for (unsigned i = 0; i < 10; i++) {
        uint8_t b, f;
        uint32_t t;
        assert_true(km_rx_queue_pop(&s_q, &b, &t, &f));
        assert_int_equal(b, 0xF0u + i);
        assert_int_equal(t, 1000u + i);
        assert_int_equal(f, 0);
    }
    uint8_t b, f;
    uint32_t t;
    assert_false(km_rx_queue_pop(&s_q, &b, &t, &f));
}

/* A full queue drops the byte, counts it, and marks the next stored byte as
 * following a loss so the parser drops the frame it belonged to. */
static void test_full_queue_marks_loss(void **state)
{
    (void)state;
    km_rx_queue_init(&s_q);
    for (unsigned i = 0; i < KM_RX_QUEUE_SIZE; i++) {
        km_rx_queue_push(&s_q, (uint8_t)i, i, false);
    }
    km_rx_queue_push(&s_q, 0xEE, 9999, false); /* dropped */
    assert_int_equal(s_q.dropped, 1);
    uint8_t b, f;
    uint32_t t;
    for (unsigned i = 0; i < KM_RX_QUEUE_SIZE; i++) {
        assert_true(km_rx_queue_pop(&s_q, &b, &t, &f));
        assert_int_equal(b, (uint8_t)i);
        assert_int_equal(f, 0);
    }
    km_rx_queue_push(&s_q, 0x42, 5, false);
    assert_true(km_rx_queue_pop(&s_q, &b, &t, &f));
    assert_int_equal(b, 0x42);
    assert_int_equal(f, KM_RX_LOST);
    km_rx_queue_push(&s_q, 0x43, 6, true); /* hardware-reported loss passes through */
    assert_true(km_rx_queue_pop(&s_q, &b, &t, &f));
    assert_int_equal(f, KM_RX_LOST);
}

/* The interrupt's fast path (km_rx_queue_try_push) stores nothing while a
 * drop waits to be marked, even with room again, and nothing into a full
 * queue: those bytes go to km_rx_queue_push, which marks the first one. */
static void test_try_push_refuses_while_a_loss_waits(void **state)
{
    (void)state;
    km_rx_queue_init(&s_q);
    for (unsigned i = 0; i < KM_RX_QUEUE_SIZE; i++) {
        assert_true(km_rx_queue_try_push(&s_q, (uint8_t)i, i));
    }
    assert_false(km_rx_queue_try_push(&s_q, 0xEE, 999)); /* full */
    assert_int_equal(s_q.dropped, 0);                    /* and nothing counted */
    km_rx_queue_push(&s_q, 0xEE, 999, false);            /* dropped */
    uint8_t b, f;
    uint32_t t;
    assert_true(km_rx_queue_pop(&s_q, &b, &t, &f)); /* room for one again */
    assert_false(km_rx_queue_try_push(&s_q, 0x42, 5));
    km_rx_queue_push(&s_q, 0x42, 5, false);
    assert_false(km_rx_queue_try_push(&s_q, 0x43, 6)); /* full again */
    for (unsigned i = 1; i < KM_RX_QUEUE_SIZE; i++) {
        assert_true(km_rx_queue_pop(&s_q, &b, &t, &f));
        assert_int_equal(f, 0);
    }
    assert_true(km_rx_queue_pop(&s_q, &b, &t, &f));
    assert_int_equal(b, 0x42);
    assert_int_equal(f, KM_RX_LOST);
    assert_true(km_rx_queue_try_push(&s_q, 0x44, 7)); /* the loss marked: the fast path again */
    assert_true(km_rx_queue_pop(&s_q, &b, &t, &f));
    assert_int_equal(b, 0x44);
    assert_int_equal(f, 0);
}

/* Indices are free-running; many laps must keep order. */
static void test_index_wrap_many_laps(void **state)
{
    (void)state;
    km_rx_queue_init(&s_q);
    uint32_t next_in = 0, next_out = 0;
    for (unsigned lap = 0; lap < 1000; lap++) {
        unsigned burst = 1u + (lap * 37u) % KM_RX_QUEUE_SIZE;
        for (unsigned i = 0; i < burst; i++, next_in++) {
            km_rx_queue_push(&s_q, (uint8_t)next_in, next_in, false);
        }
        uint8_t b, f;
        uint32_t t;
        while (km_rx_queue_pop(&s_q, &b, &t, &f)) {
            assert_int_equal(b, (uint8_t)next_out);
            assert_int_equal(t, next_out);
            next_out++;
        }
    }
    assert_int_equal(next_in, next_out);
    assert_int_equal(s_q.dropped, 0);
}

/* A run ends at the queue's end and before a byte that follows a loss; a
 * loss is told with the run that starts at its byte, once. */
static void test_peek_runs_stop_at_end_and_at_loss(void **state)
{
    (void)state;
    km_rx_queue_init(&s_q);
    km_rx_run_t run;
    assert_false(km_rx_queue_peek(&s_q, &run));
    /* Move the indices to 120 so the next run meets the queue's end. */
    for (unsigned i = 0; i < 120; i++) {
        km_rx_queue_push(&s_q, 0, 0, false);
    }
    assert_true(km_rx_queue_peek(&s_q, &run));
    assert_int_equal(run.n, 120);
    km_rx_queue_release(&s_q, 120);
    for (unsigned i = 0; i < 12; i++) {
        km_rx_queue_push(&s_q, (uint8_t)i, 500u + i, i == 5u || i == 6u);
    }
    assert_true(km_rx_queue_peek(&s_q, &run)); /* 0..4: before the first loss */
    assert_int_equal(run.n, 5);
    assert_false(run.lost);
    assert_int_equal(run.bytes[4], 4);
    assert_int_equal(run.ticks[4], 504);
    km_rx_queue_release(&s_q, 2); /* part of it: the rest comes again */
    assert_true(km_rx_queue_peek(&s_q, &run));
    assert_int_equal(run.n, 3);
    assert_int_equal(run.bytes[0], 2);
    km_rx_queue_release(&s_q, 3);
    assert_true(km_rx_queue_peek(&s_q, &run)); /* byte 5 alone: 6 follows a loss too */
    assert_true(run.lost);
    assert_int_equal(run.n, 1);
    assert_int_equal(run.bytes[0], 5);
    km_rx_queue_release(&s_q, 1);
    assert_true(km_rx_queue_peek(&s_q, &run)); /* 6, 7: the queue's end at 128 */
    assert_true(run.lost);
    assert_int_equal(run.n, 2);
    km_rx_queue_release(&s_q, 2);
    assert_true(km_rx_queue_peek(&s_q, &run)); /* 8..11 from the queue's start */
    assert_false(run.lost);
    assert_int_equal(run.n, 4);
    assert_int_equal(run.bytes[0], 8);
    assert_ptr_equal(run.bytes, &s_q.byte[0]);
    km_rx_queue_release(&s_q, 4);
    assert_false(km_rx_queue_peek(&s_q, &run));
    assert_true(km_rx_queue_empty(&s_q));
}

/* A slot that held a byte after a loss holds an unmarked byte when it
 * comes round again, whether the marked byte was taken by pop or by a run
 * (the push of an unmarked byte stores no flag: the consumer clears it). */
static void test_marked_slot_reused_unmarked(void **state)
{
    (void)state;
    km_rx_queue_init(&s_q);
    for (unsigned by_run = 0; by_run < 2u; by_run++) {
        km_rx_queue_push(&s_q, 0x55, 1, true);
        uint8_t b, f;
        uint32_t t;
        km_rx_run_t run;
        if (by_run) {
            assert_true(km_rx_queue_peek(&s_q, &run));
            assert_true(run.lost);
            km_rx_queue_release(&s_q, 1);
        } else {
            assert_true(km_rx_queue_pop(&s_q, &b, &t, &f));
            assert_int_equal(f, KM_RX_LOST);
        }
        /* a whole lap: the last byte lands in the marked byte's slot */
        for (unsigned i = 0; i < KM_RX_QUEUE_SIZE; i++) {
            km_rx_queue_push(&s_q, (uint8_t)i, i, false);
        }
        for (unsigned i = 0; i < KM_RX_QUEUE_SIZE; i++) {
            assert_true(km_rx_queue_pop(&s_q, &b, &t, &f));
            assert_int_equal(b, (uint8_t)i);
            assert_int_equal(f, 0);
        }
        assert_true(km_rx_queue_empty(&s_q));
    }
}

/* Seeded: pushes (some lost, some dropped on a full queue) interleaved with
 * peeks and partial releases hand out the very bytes, ticks and losses that
 * pop would, in order. */
static void test_peek_release_equals_pop(void **state)
{
    (void)state;
    static km_rx_queue_t a;
    static km_rx_queue_t b;
    km_rx_queue_init(&a);
    km_rx_queue_init(&b);
    uint32_t rng = 0x2545F491u;
    uint32_t seq = 0;
    unsigned losses = 0;
    for (unsigned step = 0; step < 20000; step++) {
        rng ^= rng << 13;
        rng ^= rng >> 17;
        rng ^= rng << 5;
        for (unsigned k = rng % 40u; k > 0u; k--) {
            const bool lost = (rng >> 8) % 50u == 0u && k == 1u;
            km_rx_queue_push(&a, (uint8_t)seq, seq, lost);
            km_rx_queue_push(&b, (uint8_t)seq, seq, lost);
            seq++;
        }
        km_rx_run_t run;
        if (!km_rx_queue_peek(&b, &run)) {
            assert_false(km_rx_queue_pop(&a, &(uint8_t){0}, &(uint32_t){0}, &(uint8_t){0}));
            continue;
        }
        const uint32_t take = 1u + (rng >> 16) % run.n;
        for (uint32_t i = 0; i < take; i++) {
            uint8_t byte;
            uint32_t tick;
            uint8_t flags;
            assert_true(km_rx_queue_pop(&a, &byte, &tick, &flags));
            assert_int_equal(byte, run.bytes[i]);
            assert_int_equal(tick, run.ticks[i]);
            /* Only a run's first byte can follow a loss. */
            assert_int_equal((flags & KM_RX_LOST) != 0u, i == 0u && run.lost);
            losses += (flags & KM_RX_LOST) != 0u;
        }
        km_rx_queue_release(&b, take);
    }
    assert_true(losses > 10u && a.dropped > 10u);
    assert_int_equal(a.dropped, b.dropped);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fifo_order_and_ticks),
        cmocka_unit_test(test_full_queue_marks_loss),
        cmocka_unit_test(test_try_push_refuses_while_a_loss_waits),
        cmocka_unit_test(test_index_wrap_many_laps),
        cmocka_unit_test(test_peek_runs_stop_at_end_and_at_loss),
        cmocka_unit_test(test_marked_slot_reused_unmarked),
        cmocka_unit_test(test_peek_release_equals_pop),
    };
    return cmocka_run_group_tests_name("rx_queue", tests, NULL, NULL);
}
