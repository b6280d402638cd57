/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: the system. Reset, watchdog, interrupt lock, identity. */
#ifndef KM_HAL_SYSTEM_H
#define KM_HAL_SYSTEM_H

#include <stdint.h>

/* Clocks, vector table, anything the board needs before the other inits. */
void km_hal_system_init(void);

/* Reset the MCU now (0x02 restart). Does not return. */
_Noreturn void km_hal_system_reset(void);

/* Start the watchdog with a timeout in ms; km_hal_watchdog_kick() must be
 * called more often than that. Once started it cannot be stopped. */
void km_hal_watchdog_start(uint32_t timeout_ms);
void km_hal_watchdog_kick(void);

/* Mask interrupts; returns the previous state for km_hal_irq_restore(). Used
 * around the few words main and the RX interrupt share. */
uint32_t km_hal_irq_lock(void);
void km_hal_irq_restore(uint32_t state);

/* 32 bits that differ between parts (unique ID, ADC noise...), used to seed
 * the PRNG behind the status read's random byte (§5.1 0x01). */
uint32_t km_hal_entropy(void);

/* Why the MCU last came out of reset, read once at boot (reported over 0x7F, docs/protocol-decisions.md). */
typedef enum {
    KM_RESET_POWER_ON = 0, /* power applied (or no flag the board can read) */
    KM_RESET_PIN = 1,      /* the reset pin / debugger */
    KM_RESET_SOFTWARE = 2, /* km_hal_system_reset(): a 0x02 restart */
    KM_RESET_WATCHDOG = 3, /* the watchdog was not kicked in time */
    KM_RESET_FAULT = 4,    /* a HardFault (or lockup) handler reset the MCU */
    KM_RESET_BROWNOUT = 5, /* supply dipped below the brown-out level */
    KM_RESET_OTHER = 6,    /* a flag this contract has no name for */
} km_reset_cause_t;

km_reset_cause_t km_hal_reset_cause(void);

/* Sleep until the next interrupt, called with the interrupt lock held; returns within 1 ms. */
void km_hal_idle(void);

#endif
