/* SPDX-License-Identifier: Apache-2.0 */
/* Template: reset, watchdog, interrupt lock, identity, idle (km_hal_system.h). */
#include "km_hal_system.h"

/* Clocks to full speed, flash wait states, anything other inits rely on. */
void km_hal_system_init(void)
{
}

/* Request a system reset (AIRCR.SYSRESETREQ on Cortex-M) and wait for it. */
_Noreturn void km_hal_system_reset(void)
{
    for (;;) {
    }
}

/* Why the MCU last came out of reset, read once at boot (docs/architecture.md
 * "Filling in the template"); POWER_ON until the board reads one. */
km_reset_cause_t km_hal_reset_cause(void)
{
    return KM_RESET_POWER_ON;
}

/* Start the independent watchdog with at least `timeout_ms`; it cannot be
 * stopped afterwards. */
void km_hal_watchdog_start(uint32_t timeout_ms)
{
    (void)timeout_ms;
}

/* Reload the watchdog counter. */
void km_hal_watchdog_kick(void)
{
}

/* Cortex-M: read PRIMASK, then cpsid i; return what was read. */
uint32_t km_hal_irq_lock(void)
{
    return 0u;
}

/* Cortex-M: write PRIMASK back (never a blind cpsie: locks nest). */
void km_hal_irq_restore(uint32_t state)
{
    (void)state;
}

/* Unique-ID words, a hardware RNG, or ADC noise: differs between parts. */
uint32_t km_hal_entropy(void)
{
    return 0u;
}

/* WFI: sleep until the next interrupt. */
void km_hal_idle(void)
{
}

/* Cortex-M: SCR.SLEEPONEXIT, WFI, PRIMASK to `state` (the handlers run, the
 * core sleeps again after each that does not wake), lock, SCR cleared; the
 * periodic wake-up calls km_hal_wake() (boards/common/km_cortex_m.h). */
void km_hal_sleep(uint32_t state)
{
    (void)state;
}

/* Cortex-M: clear SCR.SLEEPONEXIT; in RAM where flash work stalls fetches. */
void km_hal_wake(void)
{
}
