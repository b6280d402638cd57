/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: a wrapping tick and the answer's one-shot timer. */
#ifndef KM_HAL_TIME_H
#define KM_HAL_TIME_H

#include <stdint.h>

/* Ticks per microsecond, fixed when compiling so that converting ticks and
 * microseconds costs no division: 1 unless a board defines it for the whole
 * build (its km_hal_time_tick_hz() then returns KM_HAL_TICK_MHZ MHz). */
#ifndef KM_HAL_TICK_MHZ
#define KM_HAL_TICK_MHZ 1u
#endif

/* Ticks per second: KM_HAL_TICK_MHZ MHz. */
uint32_t km_hal_time_tick_hz(void);

void km_hal_time_init(void);

/* The tick; from any context. */
uint32_t km_hal_time_now(void);

typedef void (*km_timer_handler_t)(void *ctx);

/* Calls `handler` in interrupt context at tick `at`, replacing a pending shot. */
void km_hal_timer_at(uint32_t at, km_timer_handler_t handler, void *ctx);

void km_hal_timer_cancel(void);

#endif
