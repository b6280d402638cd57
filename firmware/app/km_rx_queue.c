/* SPSC receive queue: see km_rx_queue.h for why it exists and its ordering. */
#include "km_rx_queue.h"

void km_rx_queue_init(km_rx_queue_t *q)
{
    atomic_init(&q->head, 0u);
    atomic_init(&q->tail, 0u);
    q->dropped = 0;
    q->pending_loss = false;
}

void km_rx_queue_push(km_rx_queue_t *q, uint8_t byte, uint32_t tick, bool lost)
{
    const unsigned head = atomic_load_explicit(&q->head, memory_order_relaxed);
    const unsigned tail = atomic_load_explicit(&q->tail, memory_order_acquire);
    if (head - tail >= KM_RX_QUEUE_SIZE) {
        q->dropped++;
        q->pending_loss = true;
        return;
    }
    const unsigned slot = head & (KM_RX_QUEUE_SIZE - 1u);
    q->byte[slot] = byte;
    q->tick[slot] = tick;
    q->flags[slot] = (lost || q->pending_loss) ? KM_RX_LOST : 0u;
    q->pending_loss = false;
    /* Release: the entry is complete before the consumer can see it. */
    atomic_store_explicit(&q->head, head + 1u, memory_order_release);
}

bool km_rx_queue_pop(km_rx_queue_t *q, uint8_t *byte, uint32_t *tick, uint8_t *flags)
{
    const unsigned tail = atomic_load_explicit(&q->tail, memory_order_relaxed);
    const unsigned head = atomic_load_explicit(&q->head, memory_order_acquire);
    if (head == tail) {
        return false;
    }
    const unsigned slot = tail & (KM_RX_QUEUE_SIZE - 1u);
    *byte = q->byte[slot];
    *tick = q->tick[slot];
    *flags = q->flags[slot];
    /* Release: the slot is read before the producer may reuse it. */
    atomic_store_explicit(&q->tail, tail + 1u, memory_order_release);
    return true;
}

bool km_rx_queue_empty(km_rx_queue_t *q)
{
    return atomic_load_explicit(&q->head, memory_order_acquire) ==
           atomic_load_explicit(&q->tail, memory_order_relaxed);
}
