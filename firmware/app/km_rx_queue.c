/* SPDX-License-Identifier: Apache-2.0 */
/* SPSC receive queue (km_rx_queue.h). */
#include "km_rx_queue.h"

#include <string.h>

/* km_rx_queue_release one call in the 32 KiB build (KM_PROTOCOL_COMPACT, set for all of it:
 * docs/footprint.md). */
#if defined(KM_PROTOCOL_COMPACT) && KM_PROTOCOL_COMPACT
#define PRV_RELEASE_NOINLINE __attribute__((noinline))
#else
#define PRV_RELEASE_NOINLINE
#endif

void km_rx_queue_init(km_rx_queue_t *q)
{
    atomic_init(&q->head, 0u);
    atomic_init(&q->tail, 0u);
    atomic_init(&q->marks, 0u);
    q->marks_taken = 0;
    q->run_lost = false;
    q->dropped = 0;
    q->room = KM_RX_QUEUE_SIZE;
    memset(q->flags, 0, sizeof q->flags);
}

void km_rx_queue_push_marked(km_rx_queue_t *q, uint8_t byte, uint32_t tick, bool lost)
{
    const unsigned head = atomic_load_explicit(&q->head, memory_order_relaxed);
    const unsigned tail = atomic_load_explicit(&q->tail, memory_order_relaxed);
    atomic_signal_fence(memory_order_acquire);
    if (head - tail >= KM_RX_QUEUE_SIZE) {
        q->dropped++;
        q->room = 0u; /* the next byte comes here, to be marked */
        return;
    }
    const unsigned slot = head & (KM_RX_QUEUE_SIZE - 1u);
    q->byte[slot] = byte;
    q->tick[slot] = tick;
    if (lost || q->room == 0u) {
        q->flags[slot] = KM_RX_LOST; /* the consumer clears it when it takes the byte */
        q->room = KM_RX_QUEUE_SIZE;
        /* one writer: a plain load and store, published with head */
        atomic_store_explicit(&q->marks, atomic_load_explicit(&q->marks, memory_order_relaxed) + 1u,
                              memory_order_relaxed);
    }
    /* Release: the entry is complete before the consumer can see it. */
    atomic_signal_fence(memory_order_release);
    atomic_store_explicit(&q->head, head + 1u, memory_order_relaxed);
}

bool km_rx_queue_pop(km_rx_queue_t *q, uint8_t *byte, uint32_t *tick, uint8_t *flags)
{
    const unsigned tail = atomic_load_explicit(&q->tail, memory_order_relaxed);
    const unsigned head = atomic_load_explicit(&q->head, memory_order_relaxed);
    atomic_signal_fence(memory_order_acquire); /* the entry is read after head */
    if (head == tail) {
        return false;
    }
    const unsigned slot = tail & (KM_RX_QUEUE_SIZE - 1u);
    *byte = q->byte[slot];
    *tick = q->tick[slot];
    *flags = q->flags[slot];
    if (*flags & KM_RX_LOST) {
        q->marks_taken++;
        q->flags[slot] = 0u; /* taken: the slot's next byte is unmarked unless marked again */
    }
    /* Release: the slot is read before the producer may reuse it. */
    atomic_signal_fence(memory_order_release);
    atomic_store_explicit(&q->tail, tail + 1u, memory_order_relaxed);
    return true;
}

bool km_rx_queue_empty(km_rx_queue_t *q)
{
    return atomic_load_explicit(&q->head, memory_order_relaxed) ==
           atomic_load_explicit(&q->tail, memory_order_relaxed);
}

bool km_rx_queue_peek(km_rx_queue_t *q, km_rx_run_t *run)
{
    const unsigned tail = atomic_load_explicit(&q->tail, memory_order_relaxed);
    const unsigned head = atomic_load_explicit(&q->head, memory_order_relaxed);
    atomic_signal_fence(memory_order_acquire); /* the entries are read after head */
    if (head == tail) {
        return false;
    }
    const unsigned slot = tail & (KM_RX_QUEUE_SIZE - 1u);
    uint32_t n = head - tail;
    if (n > KM_RX_QUEUE_SIZE - slot) {
        n = KM_RX_QUEUE_SIZE - slot; /* up to the queue's end */
    }
    run->bytes = &q->byte[slot];
    run->ticks = &q->tick[slot];
    run->lost = false;
    /* read after head: covers every mark among the bytes seen */
    if (atomic_load_explicit(&q->marks, memory_order_relaxed) != q->marks_taken) {
        run->lost = (q->flags[slot] & KM_RX_LOST) != 0u;
        for (uint32_t i = 1; i < n; i++) {
            if (q->flags[slot + i] & KM_RX_LOST) {
                n = i; /* the parser must hear of that loss before that byte */
                break;
            }
        }
    }
    q->run_lost = run->lost;
    run->n = n;
    return true;
}

PRV_RELEASE_NOINLINE void km_rx_queue_release(km_rx_queue_t *q, uint32_t n)
{
    if (n == 0u) {
        return;
    }
    const unsigned tail = atomic_load_explicit(&q->tail, memory_order_relaxed);
    if (q->run_lost) {
        q->marks_taken++;
        q->run_lost = false;
        q->flags[tail & (KM_RX_QUEUE_SIZE - 1u)] = 0u; /* the run's first byte, the only marked one */
    }
    /* Release: the bytes are read before the producer may reuse them. */
    atomic_signal_fence(memory_order_release);
    atomic_store_explicit(&q->tail, tail + n, memory_order_relaxed);
}
