/* host-sim: time from CLOCK_MONOTONIC at 1 MHz, and the one-shot timer that
 * km_hal_idle() services. */
#define _POSIX_C_SOURCE 200809L
#include <stdbool.h>
#include <stddef.h>
#include <time.h>

#include "hs_io.h"
#include "km_hal_time.h"

static km_timer_handler_t s_handler;
static void *s_ctx;
static uint32_t s_at;
static bool s_armed;

uint32_t km_hal_time_tick_hz(void)
{
    return 1000000u;
}

void km_hal_time_init(void)
{
    s_armed = false;
}

uint32_t km_hal_time_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    const uint64_t us = (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
    return (uint32_t)us; /* wraps like a 32-bit hardware counter */
}

void km_hal_timer_at(uint32_t at, km_timer_handler_t handler, void *ctx)
{
    s_handler = handler;
    s_ctx = ctx;
    s_at = at;
    s_armed = true;
}

void km_hal_timer_cancel(void)
{
    s_armed = false;
}

int64_t hs_timer_due_in_us(void)
{
    if (!s_armed) {
        return -1;
    }
    const int32_t left = (int32_t)(s_at - km_hal_time_now());
    return left > 0 ? left : 0;
}

void hs_timer_service(void)
{
    if (s_armed && (int32_t)(km_hal_time_now() - s_at) >= 0) {
        s_armed = false;
        s_handler(s_ctx);
    }
}
