/* SPDX-License-Identifier: Apache-2.0 */
/* UART smoke image for qemu-microbit: proves the RX interrupt, TX and the
 * one-shot timer together, the way the firmware answers a frame. Sends the
 * banner "KMQ\n" at boot, then for every received byte, after a fixed
 * response delay measured from the byte's RX tick, sends 7 bytes:
 *   byte, dt (u32 LE: ticks since the previous RX byte),
 *   lateness (u16 LE: ticks from RX tick + delay to the timer handler).
 * Driven by tests/qemu/uart_echo.py over a TCP serial port. */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "km_hal_system.h"
#include "km_hal_time.h"
#include "km_hal_uart.h"

#define PRV_BAUD 115200u
#define PRV_DELAY_US 500u
#define PRV_RING 16u /* power of two */

typedef struct {
    uint8_t byte;
    uint32_t tick;
} prv_rx_t;

/* Single producer (UART ISR) / single consumer (main) ring. */
static prv_rx_t s_ring[PRV_RING];
static volatile uint32_t s_head;
static volatile uint32_t s_tail;
static volatile bool s_fired;
static volatile uint32_t s_fired_tick;

static void ISR_on_rx(void *ctx, uint8_t byte, uint32_t tick, bool lost)
{
    (void)ctx;
    (void)lost;
    uint32_t head = s_head;
    if (head - s_tail < PRV_RING) {
        s_ring[head % PRV_RING] = (prv_rx_t){.byte = byte, .tick = tick};
        s_head = head + 1u;
    }
}

static void ISR_on_timer(void *ctx)
{
    (void)ctx;
    s_fired_tick = km_hal_time_now();
    s_fired = true;
}

/* Sleep only if nothing is pending yet: with interrupts masked, an event
 * arriving between the check and WFI still wakes WFI (ARMv6-M), where an
 * unmasked check could miss it and sleep until some unrelated interrupt. */
static void prv_idle_unless(const volatile bool *flag, bool want)
{
    uint32_t irq = km_hal_irq_lock();
    if (*flag != want) {
        km_hal_idle();
    }
    km_hal_irq_restore(irq);
}

static void prv_put_u32(uint8_t *p, uint32_t v)
{
    for (uint32_t i = 0; i < 4u; i++) {
        p[i] = (uint8_t)(v >> (8u * i));
    }
}

int main(void)
{
    static const uint8_t s_banner[] = {'K', 'M', 'Q', '\n'};
    static uint8_t s_reply[7];
    uint32_t prev_tick = 0u;

    km_hal_system_init();
    km_hal_time_init();
    (void)km_hal_uart_init(PRV_BAUD, ISR_on_rx, NULL);
    (void)km_hal_uart_send(s_banner, sizeof s_banner);

    for (;;) {
        uint32_t irq = km_hal_irq_lock();
        if (s_head == s_tail) {
            km_hal_idle(); /* see prv_idle_unless */
            km_hal_irq_restore(irq);
            continue;
        }
        km_hal_irq_restore(irq);
        prv_rx_t rx = s_ring[s_tail % PRV_RING];
        s_tail = s_tail + 1u;

        uint32_t due = rx.tick + PRV_DELAY_US;
        s_fired = false;
        km_hal_timer_at(due, ISR_on_timer, NULL);
        while (!s_fired) {
            prv_idle_unless(&s_fired, true);
        }
        while (km_hal_uart_tx_busy()) {
            /* spin: at most one 7-byte reply (0.6 ms) is still going out */
        }
        uint32_t late = s_fired_tick - due;
        s_reply[0] = rx.byte;
        prv_put_u32(&s_reply[1], rx.tick - prev_tick);
        s_reply[5] = (uint8_t)(late > 0xFFFFu ? 0xFFu : late);
        s_reply[6] = (uint8_t)(late > 0xFFFFu ? 0xFFu : late >> 8);
        prev_tick = rx.tick;
        (void)km_hal_uart_send(s_reply, sizeof s_reply);
    }
}
