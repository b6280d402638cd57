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

/* Sleep until the next interrupt (WFI) when the main loop has nothing to do.
 * Called with the interrupt lock held (so a byte that arrives between the
 * main loop's last check and the sleep still wakes it). Returns at the
 * latest 1 ms later: the board keeps a periodic wake-up for the control tick. */
void km_hal_idle(void);

#endif
