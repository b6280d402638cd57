/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: the emulated clock at 1 MHz, held at the earliest unserviced event,
 * the one-shot timer, and km_hal_idle()'s servicing (docs/architecture.md
 * "host-sim's clock"). */
#define _POSIX_C_SOURCE 200809L
#include <stdbool.h>
#include <stddef.h>
#include <time.h>

#include "hs_io.h"
#include "km_hal_time.h"

static km_timer_handler_t s_handler;
static void *s_ctx;
static uint64_t s_at_ns; /* the armed timer's due time */
static bool s_armed;
static uint64_t s_last_ns;       /* keeps the clock monotonic across holds */
static uint64_t s_firing_due_ns; /* inside the handler: the timer's due time */

uint32_t km_hal_time_tick_hz(void)
{
    return KM_HAL_TICK_MHZ * 1000000u;
}

void km_hal_time_init(void)
{
    s_armed = false;
}

uint64_t hs_time_real_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

uint64_t hs_time_now_ns(void)
{
    uint64_t t = hs_time_real_ns();
    if (s_armed && s_at_ns < t) {
        t = s_at_ns;
    }
    const uint64_t uart = hs_uart_hold_ns();
    if (uart < t) {
        t = uart;
    }
    if (t < s_last_ns) {
        t = s_last_ns; /* an event armed in the past: it runs now, late */
    }
    s_last_ns = t;
    return t;
}

uint32_t km_hal_time_now(void)
{
    return (uint32_t)(hs_time_now_ns() / 1000u); /* wraps like a 32-bit hardware counter */
}

void km_hal_timer_at(uint32_t at, km_timer_handler_t handler, void *ctx)
{
    const uint64_t now_ns = hs_time_now_ns();
    const uint32_t now = (uint32_t)(now_ns / 1000u);
    /* Unsigned tick difference; a due time in the past fires at once. */
    const int32_t ahead = (int32_t)(at - now);
    s_at_ns = (now_ns / 1000u) * 1000u + (uint64_t)((int64_t)ahead * 1000);
    s_handler = handler;
    s_ctx = ctx;
    s_armed = true;
}

static void prv_timer_fire_due(uint64_t now_ns);

void km_hal_timer_cancel(void)
{
    /* A due shot runs before the cancel, as on an MCU. */
    prv_timer_fire_due(hs_time_now_ns());
    s_armed = false;
}

int64_t hs_timer_due_in_us(void)
{
    /* Wake-ups are in host time. */
    const uint64_t real = hs_time_real_ns();
    int64_t due = -1;
    if (s_armed) {
        due = s_at_ns > real ? (int64_t)((s_at_ns - real + 999u) / 1000u) : 0;
    }
    /* A byte or TX done is an interrupt too. */
    const int64_t uart = hs_uart_due_in_us(real);
    if (uart >= 0 && (due < 0 || uart < due)) {
        due = uart;
    }
    return due;
}

static void prv_timer_fire_due(uint64_t now_ns)
{
    if (s_armed && s_at_ns <= now_ns) {
        s_armed = false;
        s_firing_due_ns = s_at_ns;
        s_handler(s_ctx);
        s_firing_due_ns = 0;
    }
}

uint64_t hs_timer_firing_due_ns(void)
{
    return s_firing_due_ns;
}

void hs_timer_fire_due_now(void)
{
    prv_timer_fire_due(hs_time_real_ns());
}

void hs_timer_service(void)
{
    hs_uart_rx_idle_begin(); /* before the timer may put an answer on the wire */
    /* In time order; at most HS_RX_BATCH bytes, one frame end per idle. */
    for (unsigned n = 0;; n++) {
        prv_timer_fire_due(hs_time_now_ns());
        if (n == HS_RX_BATCH || !hs_uart_rx_deliver_one()) {
            break;
        }
    }
}
