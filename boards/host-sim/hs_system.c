/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: system services. A restart re-executes the program with the same
 * arguments, which keeps the flash file, as a real MCU keeps its flash; the
 * watchdog is a deadline checked at each idle. The reset cause crosses the
 * re-execution in the environment (KM_HS_RESET_CAUSE), as the bus
 * descriptors do (hs_uart_prepare_exec): a process started by hand has no
 * such variable and reads as a power-on. */
#define _GNU_SOURCE /* ppoll: a microsecond timeout for the answer timer */
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#include "hs_io.h"
#include "km_hal_system.h"
#include "km_hal_time.h"

#define PRV_CAUSE_ENV "KM_HS_RESET_CAUSE"

static char **s_argv;
static uint32_t s_wdt_timeout_us;
static uint32_t s_wdt_last;
static km_reset_cause_t s_cause;
static int s_cause_read;

/* Once per process: what the previous image left in the environment, then
 * removed, so nothing started from here inherits a stale cause. */
static void prv_capture_cause(void)
{
    if (s_cause_read) {
        return;
    }
    s_cause_read = 1;
    s_cause = KM_RESET_POWER_ON;
    const char *v = getenv(PRV_CAUSE_ENV);
    if (v != NULL) {
        char *end = NULL;
        long c = strtol(v, &end, 10);
        if (end != v && *end == '\0' && c >= KM_RESET_POWER_ON && c <= KM_RESET_OTHER) {
            s_cause = (km_reset_cause_t)c;
        }
        unsetenv(PRV_CAUSE_ENV);
    }
}

km_reset_cause_t km_hal_reset_cause(void)
{
    prv_capture_cause();
    return s_cause;
}

/* Re-execute the program, telling the next image why. */
_Noreturn static void prv_restart(km_reset_cause_t cause)
{
    char buf[4];
    snprintf(buf, sizeof buf, "%d", (int)cause);
    setenv(PRV_CAUSE_ENV, buf, 1);
    fflush(NULL);
    hs_uart_prepare_exec();
    hs_plant_prepare_exec();
    execv("/proc/self/exe", s_argv);
    perror("host-sim: restart failed");
    exit(3);
}

void hs_system_set_argv(char **argv)
{
    s_argv = argv;
}

void km_hal_system_init(void)
{
    prv_capture_cause();
}

_Noreturn void km_hal_system_reset(void)
{
    prv_restart(KM_RESET_SOFTWARE);
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
        prv_restart(KM_RESET_WATCHDOG);
    }
    /* Wait for bus input, but never past the timer or the next control tick. */
    int64_t wait_us = hs_timer_due_in_us();
    if (wait_us < 0 || wait_us > 1000) {
        wait_us = 1000;
    }
    struct pollfd pfd[2] = {{.fd = hs_uart_poll_fd(), .events = POLLIN},
                            {.fd = hs_inject_poll_fd(), .events = POLLIN}};
    const struct timespec timeout = {.tv_sec = 0, .tv_nsec = (long)wait_us * 1000L};
    if (ppoll(pfd, 2u, &timeout, NULL) > 0) { /* a negative fd is ignored */
        if (pfd[0].revents & POLLIN) {
            hs_uart_on_readable();
        }
        if (pfd[1].revents & POLLIN) {
            hs_inject_on_readable();
        }
    }
    hs_timer_service();
}

/* The "interrupts" run inside km_hal_idle(): it returns after each batch. */
void km_hal_sleep(uint32_t state)
{
    (void)state;
    km_hal_idle();
}

/* km_hal_sleep() returns after every batch anyway. */
void km_hal_wake(void)
{
}
