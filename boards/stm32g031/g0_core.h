/* SPDX-License-Identifier: Apache-2.0 */
/* Cortex-M0+ core registers the board uses (ARMv6-M ARM B3.2, B3.4; PM0223). */
#ifndef G0_CORE_H
#define G0_CORE_H

#include <stdint.h>

/* A register as a word of a 128-byte block: the compiler then reaches the
 * registers near one another from one block address in a register, not
 * one literal address each (docs/footprint.md "STM32G031F6"). */
typedef struct {
    volatile uint32_t word[32];
} g0_block_t;
/* The register `offset` bytes (below 128) from `base`. */
#define G0_REG_AT(base, offset) (((g0_block_t *)(uintptr_t)(base))->word[(offset) / 4u])
/* The register at a constant address. */
#define G0_REG(addr) G0_REG_AT((addr) & ~0x7Fu, 0x7Fu & (addr))

/* System control block (ARMv6-M B3.2.2). */
#define SCB_AIRCR G0_REG(0xE000ED0Cu)
#define SCB_AIRCR_VECTKEY (0x05FAu << 16)
#define SCB_AIRCR_SYSRESETREQ (1u << 2)
#define SCB_SHPR3 G0_REG(0xE000ED20u) /* bits 31:24 SysTick priority */
#define SCB_VTOR G0_REG(0xE000ED08u)  /* M0+ only */

/* Runs from RAM while flash is busy (docs/flash-busy.md); noinline, or it
 * would run inlined from flash. */
#define G0_RAMFUNC(name) __attribute__((section(".ramfunc." #name), noinline))

/* SysTick (ARMv6-M B3.3): 24-bit down counter on the core clock. */
#define SYST_CSR G0_REG(0xE000E010u)
#define SYST_RVR G0_REG(0xE000E014u)
#define SYST_CVR G0_REG(0xE000E018u)
#define SYST_CSR_ENABLE (1u << 0)
#define SYST_CSR_TICKINT (1u << 1)
#define SYST_CSR_CLKSOURCE (1u << 2) /* processor clock */

/* NVIC (ARMv6-M B3.4.2): 2 priority bits (7:6), IPR word access only. */
#define NVIC_ISER G0_REG(0xE000E100u)
#define NVIC_ICER G0_REG(0xE000E180u)
#define NVIC_ICPR G0_REG(0xE000E280u)
#define NVIC_IPR(n) G0_REG_AT(0xE000E400u, 4u * (uint32_t)(n))

/* Sets the priority, clears pending, enables. */
static inline void g0_nvic_enable(uint32_t irq, uint32_t prio)
{
    uint32_t shift = (irq & 3u) * 8u;
    uint32_t ipr = NVIC_IPR(irq >> 2);
    ipr &= ~(0xFFu << shift);
    ipr |= ((prio & 3u) << 6) << shift;
    NVIC_IPR(irq >> 2) = ipr;
    NVIC_ICPR = 1u << irq;
    NVIC_ISER = 1u << irq;
}

/* Disables an interrupt. */
static inline void g0_nvic_disable(uint32_t irq)
{
    NVIC_ICER = 1u << irq;
}

/* STM32G031 vector positions (RM0444 §12.3 table 61). */
#define G0_IRQ_TIM2 15u
#define G0_IRQ_USART1 27u

#endif
