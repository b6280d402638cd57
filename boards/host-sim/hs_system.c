/* host-sim: system services. A restart re-executes the program with the same
 * arguments, which keeps the flash file, as a real MCU keeps its flash; the
 * watchdog is a deadline checked at each idle. */
#define _GNU_SOURCE /* ppoll: a microsecond timeout for the answer timer */
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#include "hs_io.h"
#include "km_hal_system.h"
#include "km_hal_time.h"

static char **s_argv;
static uint32_t s_wdt_timeout_us;
static uint32_t s_wdt_last;

void hs_system_set_argv(char **argv)
{
    s_argv = argv;
}

void km_hal_system_init(void)
{
}

_Noreturn void km_hal_system_reset(void)
{
    fflush(NULL);
    hs_uart_prepare_exec();
    execv("/proc/self/exe", s_argv);
    perror("host-sim: restart failed");
    exit(3);
}

void km_hal_watchdog_start(uint32_t timeout_ms)
{
    s_wdt_timeout_us = timeout_ms * 1000u;
    s_wdt_last = km_hal_time_now();
}

void km_hal_watchdog_kick(void)
{
    s_wdt_last = km_hal_time_now();
}

uint32_t km_hal_irq_lock(void)
{
    return 0; /* handlers run only from km_hal_idle(): nothing to mask */
}

void km_hal_irq_restore(uint32_t state)
{
    (void)state;
}

uint32_t km_hal_entropy(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (uint32_t)ts.tv_nsec ^ ((uint32_t)getpid() << 16);
}

void km_hal_idle(void)
{
    if (s_wdt_timeout_us && km_hal_time_now() - s_wdt_last > s_wdt_timeout_us) {
        fprintf(stderr, "host-sim: watchdog expired, restarting\n");
        km_hal_system_reset();
    }
    /* Wait for bus input, but never past the timer or the next control tick. */
    int64_t wait_us = hs_timer_due_in_us();
    if (wait_us < 0 || wait_us > 1000) {
        wait_us = 1000;
    }
    struct pollfd pfd = {.fd = hs_uart_poll_fd(), .events = POLLIN};
    const struct timespec timeout = {.tv_sec = 0, .tv_nsec = (long)wait_us * 1000L};
    if (ppoll(&pfd, pfd.fd >= 0 ? 1u : 0u, &timeout, NULL) > 0) {
        hs_uart_on_readable();
    }
    hs_timer_service();
}
