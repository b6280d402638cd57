/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: time. A free-running monotonic tick (wraps at 2^32; callers
 * use unsigned differences) and one one-shot timer used to start the answer
 * exactly the response delay after a frame's last byte. */
#ifndef KM_HAL_TIME_H
#define KM_HAL_TIME_H

#include <stdint.h>

/* Ticks per second of km_hal_time_now(): a whole number of MHz, at least 1. */
uint32_t km_hal_time_tick_hz(void);

void km_hal_time_init(void);

/* Current tick; callable from interrupts and the main loop. */
uint32_t km_hal_time_now(void);

typedef void (*km_timer_handler_t)(void *ctx);

/* Arm the one-shot timer for `handler` (interrupt context) at tick `at`; re-arming replaces a pending shot.
 */
void km_hal_timer_at(uint32_t at, km_timer_handler_t handler, void *ctx);

void km_hal_timer_cancel(void);

#endif
