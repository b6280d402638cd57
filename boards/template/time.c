/* SPDX-License-Identifier: Apache-2.0 */
/* Template: the monotonic tick and the one-shot timer (km_hal_time.h). */
#include "km_hal_time.h"

/* Ticks per second of km_hal_time_now(): KM_HAL_TICK_MHZ (a whole number,
 * 1 unless the board's build defines it) MHz. */
uint32_t km_hal_time_tick_hz(void)
{
    return KM_HAL_TICK_MHZ * 1000000u;
}

/* Starts a free-running timer at tick_hz (32 bits, or extended in software). */
void km_hal_time_init(void)
{
}

/* Read the counter; safe from interrupts and main alike. */
uint32_t km_hal_time_now(void)
{
    return 0u;
}

/* Arms the one-shot for `at` (pended at once when not in the future); the ISR disarms, then calls. */
void km_hal_timer_at(uint32_t at, km_timer_handler_t handler, void *ctx)
{
    (void)at;
    (void)handler;
    (void)ctx;
}

/* Disarm the compare channel and forget the handler. */
void km_hal_timer_cancel(void)
{
}
