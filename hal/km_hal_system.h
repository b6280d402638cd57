/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: the system. */
#ifndef KM_HAL_SYSTEM_H
#define KM_HAL_SYSTEM_H

#include <stdint.h>

/* Clocks, vectors: first of the inits. */
void km_hal_system_init(void);

/* Resets the MCU now (0x02 restart). */
_Noreturn void km_hal_system_reset(void);

/* Starts the watchdog (timeout in ms, kicked more often); no stop. */
void km_hal_watchdog_start(uint32_t timeout_ms);
void km_hal_watchdog_kick(void);

/* Masks interrupts; returns the state km_hal_irq_restore() takes. */
uint32_t km_hal_irq_lock(void);
void km_hal_irq_restore(uint32_t state);

/* Bits that differ between parts: the seed of §5.1 0x01's random byte. */
uint32_t km_hal_entropy(void);

/* The last reset's cause (0x7F), read once at boot. */
typedef enum {
    KM_RESET_POWER_ON = 0, /* or no flag to read */
    KM_RESET_PIN = 1,
    KM_RESET_SOFTWARE = 2, /* km_hal_system_reset() */
    KM_RESET_WATCHDOG = 3,
    KM_RESET_FAULT = 4, /* HardFault or lockup */
    KM_RESET_BROWNOUT = 5,
    KM_RESET_OTHER = 6,
} km_reset_cause_t;

km_reset_cause_t km_hal_reset_cause(void);

/* Sleeps until an interrupt; lock held; returns within 1 ms. */
void km_hal_idle(void);

/* Lock held, taken from `state`: sleeps with the lock released (to `state`)
 * until a handler calls km_hal_wake(), at the latest 1 ms later; handlers
 * that do not call it go back to sleep, on a Cortex-M without running the
 * caller. It may return early. Returns with the lock held. */
void km_hal_sleep(uint32_t state);

/* Interrupt context: km_hal_sleep() returns after this interrupt. */
void km_hal_wake(void);

#endif
