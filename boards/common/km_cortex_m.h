/* SPDX-License-Identifier: Apache-2.0 */
/* ARMv6-M (Cortex-M0/M0+) core operations every Cortex-M board shares: the
 * interrupt lock behind km_hal_irq_lock()/restore() and the WFI sleep. */
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

#endif
