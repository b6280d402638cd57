/* SPDX-License-Identifier: Apache-2.0 */
/* Cortex-M0+ core registers this board touches (SCB, NVIC), from the ARMv6-M
 * Architecture Reference Manual (B3.2, B3.4) as summarised in PM0223. Only
 * what the board uses; no vendor headers. */
#ifndef G0_CORE_H
#define G0_CORE_H

#include <stdint.h>

#define G0_REG(addr) (*(volatile uint32_t *)(uintptr_t)(addr))

/* System control block (ARMv6-M B3.2.2). */
#define SCB_AIRCR G0_REG(0xE000ED0Cu)
#define SCB_AIRCR_VECTKEY (0x05FAu << 16)
#define SCB_AIRCR_SYSRESETREQ (1u << 2)
#define SCB_SHPR3 G0_REG(0xE000ED20u) /* bits 31:24 SysTick priority */
#define SCB_VTOR G0_REG(0xE000ED08u)  /* vector table offset (M0+ has it, M0 does not) */

/* A function that must run from RAM because it runs while flash is busy
 * (docs/flash-busy.md): its own section .ramfunc.<name>, which the linker
 * script places in RAM and --gc-sections can still drop. noinline: a RAM
 * function inlined into a flash caller would run from flash. */
#define G0_RAMFUNC(name) __attribute__((section(".ramfunc." #name), noinline))

/* SysTick (ARMv6-M B3.3): 24-bit down counter on the core clock. */
#define SYST_CSR G0_REG(0xE000E010u)
#define SYST_RVR G0_REG(0xE000E014u)
#define SYST_CVR G0_REG(0xE000E018u)
#define SYST_CSR_ENABLE (1u << 0)
#define SYST_CSR_TICKINT (1u << 1)
#define SYST_CSR_CLKSOURCE (1u << 2) /* processor clock */

/* NVIC (ARMv6-M B3.4.2): 32 interrupts, 2 priority bits per 8-bit field
 * (bits 7:6), priority registers word-access only on M0+. */
#define NVIC_ISER G0_REG(0xE000E100u)
#define NVIC_ICER G0_REG(0xE000E180u)
#define NVIC_ICPR G0_REG(0xE000E280u)
#define NVIC_IPR(n) G0_REG(0xE000E400u + 4u * (uint32_t)(n))

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

static inline void g0_nvic_disable(uint32_t irq)
{
    NVIC_ICER = 1u << irq;
}

/* STM32G031 vector positions (RM0444 §12.3 table 61, "Vector table"). */
#define G0_IRQ_TIM2 15u
#define G0_IRQ_USART1 27u

#endif
