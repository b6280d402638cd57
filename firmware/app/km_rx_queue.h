/* SPDX-License-Identifier: Apache-2.0 */
/* Single-producer single-consumer queue of received bus bytes and their
 * arrival ticks, from the UART receive interrupt to the main loop.
 * Lock-free on one core: the producer writes only `head`, the consumer only
 * `tail`, ordered by signal fences. A slot's LOST flag is set only while it
 * holds a marked byte not yet taken. docs/app-design.md "Receive queue". */
#ifndef KM_RX_QUEUE_H
#define KM_RX_QUEUE_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

/* Power of two: 1.1 ms of traffic at 1 Mbaud. */
#define KM_RX_QUEUE_SIZE 128u

#define KM_RX_LOST 0x01u /* bytes were lost before this one (overrun) */

typedef struct {
    /* What a push touches first: from the queue's address (or from a
     * struct that holds it after a few words), each scalar one ARMv6-M load
     * or store, a byte an add and a store (byte offsets reach 31). */
    atomic_uint head; /* written by the producer only */
    atomic_uint tail; /* written by the consumer only */
    /* Producer side: KM_RX_QUEUE_SIZE, or 0 after a byte was dropped: the
     * next byte goes to km_rx_queue_push_marked() to be marked LOST. */
    uint32_t room;
    uint8_t byte[KM_RX_QUEUE_SIZE];
    uint32_t tick[KM_RX_QUEUE_SIZE];
    /* LOST-marked bytes stored (producer) and taken (consumer): equal = none waits. */
    atomic_uint marks;
    uint32_t marks_taken;
    uint32_t dropped;                /* producer side: bytes lost because the queue was full */
    bool run_lost;                   /* consumer side: the run peeked starts with a LOST byte */
    uint8_t flags[KM_RX_QUEUE_SIZE]; /* KM_RX_LOST on a marked byte not yet taken, else 0 */
} km_rx_queue_t;

/* The oldest waiting bytes as one run, where they lie in the queue. */
typedef struct {
    const uint8_t *bytes;
    const uint32_t *ticks;
    uint32_t n; /* >= 1 */
    bool lost;  /* bytes were lost right before bytes[0] */
} km_rx_run_t;

void km_rx_queue_init(km_rx_queue_t *q);

/* Interrupt context: km_rx_queue_push's rare cases (full, after a loss). */
void km_rx_queue_push_marked(km_rx_queue_t *q, uint8_t byte, uint32_t tick, bool lost);

/* Interrupt context: stores an unmarked byte; false, storing nothing, when
 * the queue is full or a loss waits to be marked (km_rx_queue_push then). */
static inline __attribute__((always_inline)) bool km_rx_queue_try_push(km_rx_queue_t *q, uint8_t byte,
                                                                       uint32_t tick)
{
    const unsigned head = atomic_load_explicit(&q->head, memory_order_relaxed);
    const unsigned tail = atomic_load_explicit(&q->tail, memory_order_relaxed);
    atomic_signal_fence(memory_order_acquire); /* the slot was read before the consumer freed it */
    if (head - tail >= q->room) {
        return false;
    }
    const unsigned slot = head & (KM_RX_QUEUE_SIZE - 1u);
    q->byte[slot] = byte;
    q->tick[slot] = tick;
    /* Release: the entry is complete before the consumer can see it. */
    atomic_signal_fence(memory_order_release);
    atomic_store_explicit(&q->head, head + 1u, memory_order_relaxed);
    return true;
}

/* Interrupt context, every byte: a full queue drops it and marks the next.
 * always_inline: the receive interrupt's code stays where the board puts it. */
static inline __attribute__((always_inline)) void km_rx_queue_push(km_rx_queue_t *q, uint8_t byte,
                                                                   uint32_t tick, bool lost)
{
    if (lost || !km_rx_queue_try_push(q, byte, tick)) {
        km_rx_queue_push_marked(q, byte, tick, lost);
    }
}

/* Main loop: true when nothing is waiting. */
bool km_rx_queue_empty(km_rx_queue_t *q);

/* Main loop: how many bytes are waiting (a lower bound: more may arrive). */
static inline uint32_t km_rx_queue_count(km_rx_queue_t *q)
{
    return atomic_load_explicit(&q->head, memory_order_relaxed) -
           atomic_load_explicit(&q->tail, memory_order_relaxed);
}

/* Main loop. Returns false when empty. */
bool km_rx_queue_pop(km_rx_queue_t *q, uint8_t *byte, uint32_t *tick, uint8_t *flags);

/* Main loop: the oldest waiting bytes as a run, in place, up to the next
 * loss; valid until km_rx_queue_release() takes n <= run->n. False: empty. */
bool km_rx_queue_peek(km_rx_queue_t *q, km_rx_run_t *run);
void km_rx_queue_release(km_rx_queue_t *q, uint32_t n);

#endif
