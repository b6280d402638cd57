/* RX queue tests: order, ticks, full-queue loss marking, index wrap. */
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fifo_order_and_ticks),
        cmocka_unit_test(test_full_queue_marks_loss),
        cmocka_unit_test(test_index_wrap_many_laps),
    };
    return cmocka_run_group_tests_name("rx_queue", tests, NULL, NULL);
}
