/* SPDX-License-Identifier: Apache-2.0 */
/* ARMv6-M (Cortex-M0/M0+) core operations every Cortex-M board shares: the
 * interrupt lock behind km_hal_irq_lock()/restore(), the WFI sleep and the
 * sleep-on-exit behind km_hal_sleep()/km_hal_wake(). */
#ifndef KM_CORTEX_M_H
#define KM_CORTEX_M_H

#include <stdint.h>

/* Masks interrupts (PRIMASK) and returns the previous PRIMASK. */
static inline uint32_t km_cortex_irq_lock(void)
{
    uint32_t primask;
    __asm__ volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask)::"memory");
    return primask;
}

static inline void km_cortex_irq_restore(uint32_t primask)
{
    __asm__ volatile("msr primask, %0" ::"r"(primask) : "memory");
}

/* WFI wakes on any pending enabled interrupt even with PRIMASK set, so a
 * caller may check-then-sleep inside the lock without losing a wake-up. */
static inline void km_cortex_wait_for_interrupt(void)
{
    __asm__ volatile("wfi" ::: "memory");
}

/* System Control Register (ARMv6-M B3.2.7): SLEEPONEXIT, set, sends the
 * core back to sleep at every return from a handler to Thread mode. */
#define KM_CORTEX_SCR (*(volatile uint32_t *)(uintptr_t)0xE000ED10u)
#define KM_CORTEX_SCR_SLEEPONEXIT (1u << 1)

/* PRIMASK set: sleeps, the handlers running under `primask`, until one
 * calls km_cortex_wake(); the others return straight to sleep, the caller
 * runs no instruction for them. Returns with PRIMASK set and SCR clear (the
 * boards use neither SLEEPDEEP nor SEVONPEND). */
static inline void km_cortex_sleep_until_wake(uint32_t primask)
{
    KM_CORTEX_SCR = KM_CORTEX_SCR_SLEEPONEXIT;
    km_cortex_wait_for_interrupt(); /* a handler pending already: at once */
    km_cortex_irq_restore(primask); /* the handlers run, sleeping after each */
    (void)km_cortex_irq_lock();
    KM_CORTEX_SCR = 0u; /* returned without a wake: `primask` was set */
}

/* Interrupt context: the handler returns to Thread mode, not to sleep. */
static inline void km_cortex_wake(void)
{
    KM_CORTEX_SCR = 0u;
}

#endif
