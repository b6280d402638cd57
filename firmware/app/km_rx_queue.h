/* SPDX-License-Identifier: Apache-2.0 */
/* Single-producer single-consumer queue of received bus bytes, from the UART
 * receive interrupt (producer) to the main loop (consumer).
 *
 * Why a queue and not the parser in the interrupt: the parser's worst case
 * (a resync scan over up to 256 bytes after a failed frame) and the
 * dispatcher's work would then run at interrupt priority and delay the
 * answer-timer interrupt; the queue keeps the RX interrupt at a few dozen
 * instructions and lets the main loop bound its work per poll. Each entry
 * keeps the byte's arrival tick, so a frame's end is still stamped by the
 * interrupt, not by when the main loop got to it.
 *
 * Lock-free: the producer writes only `head`, the consumer only `tail`; both
 * are 32-bit words, read and written whole on Cortex-M0. Producer and
 * consumer run on one core (an interrupt and the main loop; host-sim's
 * receive runs inside km_hal_idle on its one thread), so they are ordered
 * like a signal handler and its thread: relaxed accesses and C11 signal
 * fences, which keep the compiler's order and cost no DMB.
 *
 * The LOST marks: a slot's flag is non-zero only while it holds a marked
 * byte not yet taken. The producer writes a flag only with a marked byte
 * (km_rx_queue_push_marked); the consumer clears it when it takes that
 * byte, so the push of every other byte stores no flag. */
#ifndef KM_RX_QUEUE_H
#define KM_RX_QUEUE_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

/* Power of two. 128 bytes = 1.1 ms of traffic at 1 Mbaud; the main loop
 * drains every control tick (1 ms) and more often when idle. */
#define KM_RX_QUEUE_SIZE 128u

#define KM_RX_LOST 0x01u /* bytes were lost before this one (overrun) */

typedef struct {
    /* The scalars first, the word array next: on ARMv6-M every field is
     * then one load or store from the queue pointer (immediate offsets
     * reach 124 bytes for words, 31 for bytes), which the interrupt side
     * pays per received byte. */
    atomic_uint head; /* written by the producer only */
    atomic_uint tail; /* written by the consumer only */
    /* LOST-marked bytes stored, ever (producer) and taken (consumer): while
     * they are equal no byte waiting is marked, and a run is handed out
     * without looking at one flag. */
    atomic_uint marks;
    uint32_t marks_taken;
    uint32_t dropped;               /* producer side: bytes lost because the queue was full */
    bool pending_loss;              /* producer side: mark the next stored byte as LOST */
    bool run_lost;                  /* consumer side: the run peeked starts with a LOST byte */
    uint8_t byte[KM_RX_QUEUE_SIZE]; /* right after the scalars: its base is one add away */
    uint32_t tick[KM_RX_QUEUE_SIZE];
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

/* Interrupt context, the rare cases of km_rx_queue_push: a full queue, a
 * byte after a loss. */
void km_rx_queue_push_marked(km_rx_queue_t *q, uint8_t byte, uint32_t tick, bool lost);

/* Interrupt context. A full queue drops the byte and marks the next one
 * stored as following a loss, so the parser drops the broken frame.
 * Inline: the receive interrupt pays it on every byte. */
static inline void km_rx_queue_push(km_rx_queue_t *q, uint8_t byte, uint32_t tick, bool lost)
{
    const unsigned head = atomic_load_explicit(&q->head, memory_order_relaxed);
    const unsigned tail = atomic_load_explicit(&q->tail, memory_order_relaxed);
    atomic_signal_fence(memory_order_acquire); /* the slot was read before the consumer freed it */
    if (head - tail >= KM_RX_QUEUE_SIZE || lost || q->pending_loss) {
        km_rx_queue_push_marked(q, byte, tick, lost);
        return;
    }
    const unsigned slot = head & (KM_RX_QUEUE_SIZE - 1u);
    q->byte[slot] = byte;
    q->tick[slot] = tick;
    /* Release: the entry is complete before the consumer can see it. */
    atomic_signal_fence(memory_order_release);
    atomic_store_explicit(&q->head, head + 1u, memory_order_relaxed);
}

/* Main loop: true when nothing is waiting. */
bool km_rx_queue_empty(km_rx_queue_t *q);

/* Main loop. Returns false when empty. */
bool km_rx_queue_pop(km_rx_queue_t *q, uint8_t *byte, uint32_t *tick, uint8_t *flags);

/* Main loop, the batch way (no call per byte, no copy): the oldest waiting
 * bytes, up to the queue's end and up to (not including) the next byte
 * after a loss, left in place; false when empty. The bytes stay valid and
 * in the queue until km_rx_queue_release() takes the first n of them
 * (n <= run->n), so a frame can be handled where it lies first. */
bool km_rx_queue_peek(km_rx_queue_t *q, km_rx_run_t *run);
void km_rx_queue_release(km_rx_queue_t *q, uint32_t n);

#endif
