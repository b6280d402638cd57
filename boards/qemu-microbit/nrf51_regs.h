/* SPDX-License-Identifier: Apache-2.0 */
/* nRF51 and Cortex-M0 register map: only what this board uses, written from
 * the nRF51 Series Reference Manual v3.0 and the ARMv6-M ARM. Registers are
 * reached as base + offset so every address appears exactly once here. */
/* clang-format off: register maps aligned by hand, one address per line */
#ifndef NRF51_REGS_H
#define NRF51_REGS_H

#include <stdint.h>

#define NRF_REG(base, off) (*(volatile uint32_t *)((uintptr_t)(base) + (uintptr_t)(off)))

/* Peripheral bases (RM §9 memory map). */
#define NRF_CLOCK 0x40000000u
#define NRF_UART0 0x40002000u
#define NRF_TIMER0 0x40008000u
#define NRF_RNG 0x4000D000u
#define NRF_WDT 0x40010000u
#define NRF_NVMC 0x4001E000u
#define NRF_FICR 0x10000000u
#define NRF_GPIO 0x50000000u

/* GPIO (RM §14) */
#define GPIO_OUTSET 0x508u
#define GPIO_PIN_CNF(n) (0x700u + 4u * (n))
#define GPIO_PIN_CNF_OUTPUT 1u /* DIR = output, input buffer connected */
#define GPIO_PIN_CNF_INPUT 0u  /* DIR = input, buffer connected, no pull */

/* Interrupt numbers = peripheral ID = (base >> 12) & 0x1F. */
#define NRF_IRQ_UART0 2u
#define NRF_IRQ_TIMER0 8u

/* CLOCK */
#define CLOCK_TASKS_HFCLKSTART 0x000u
#define CLOCK_EVENTS_HFCLKSTARTED 0x100u

/* UART (RM §29) */
#define UART_TASKS_STARTRX 0x000u
#define UART_TASKS_STOPRX 0x004u
#define UART_TASKS_STARTTX 0x008u
#define UART_TASKS_STOPTX 0x00Cu
#define UART_EVENTS_RXDRDY 0x108u
#define UART_EVENTS_TXDRDY 0x11Cu
#define UART_EVENTS_ERROR 0x124u
#define UART_INTENSET 0x304u
#define UART_INTENCLR 0x308u
#define UART_ERRORSRC 0x480u
#define UART_ENABLE 0x500u
#define UART_PSELRTS 0x508u
#define UART_PSELTXD 0x50Cu
#define UART_PSELCTS 0x510u
#define UART_PSELRXD 0x514u
#define UART_RXD 0x518u
#define UART_TXD 0x51Cu
#define UART_BAUDRATE 0x524u
#define UART_CONFIG 0x56Cu
#define UART_INT_RXDRDY (1u << 2)
#define UART_INT_TXDRDY (1u << 7)
#define UART_INT_ERROR (1u << 9)
#define UART_ENABLE_ENABLED 4u
#define UART_PSEL_DISCONNECTED 0xFFFFFFFFu

/* TIMER (RM §18) */
#define TIMER_TASKS_START 0x000u
#define TIMER_TASKS_STOP 0x004u
#define TIMER_TASKS_CLEAR 0x00Cu
#define TIMER_TASKS_CAPTURE(n) (0x040u + 4u * (n))
#define TIMER_EVENTS_COMPARE(n) (0x140u + 4u * (n))
#define TIMER_SHORTS 0x200u
#define TIMER_INTENSET 0x304u
#define TIMER_INTENCLR 0x308u
#define TIMER_INT_COMPARE(n) (1u << (16u + (n)))
#define TIMER_MODE 0x504u
#define TIMER_BITMODE 0x508u
#define TIMER_BITMODE_16 0u
#define TIMER_BITMODE_32 3u
#define TIMER_PRESCALER 0x510u
#define TIMER_CC(n) (0x540u + 4u * (n))

/* RNG (RM §21) */
#define RNG_TASKS_START 0x000u
#define RNG_TASKS_STOP 0x004u
#define RNG_EVENTS_VALRDY 0x100u
#define RNG_CONFIG 0x504u
#define RNG_VALUE 0x508u

/* WDT (RM §25) */
#define WDT_TASKS_START 0x000u
#define WDT_RUNSTATUS 0x400u /* bit 0: running */
#define WDT_CRV 0x504u
#define WDT_RREN 0x508u
#define WDT_CONFIG 0x50Cu
#define WDT_RR0 0x600u
#define WDT_RR_RELOAD 0x6E524635u
#define WDT_CONFIG_HALT_PAUSE 0u /* bit 3 clear: pause while the debugger halts */
#define WDT_CONFIG_SLEEP_RUN 1u  /* bit 0 set: keep counting while the CPU sleeps */

/* NVMC (RM §6) and FICR (RM §7) */
#define NVMC_READY 0x400u
#define NVMC_CONFIG 0x504u
#define NVMC_CONFIG_REN 0u
#define NVMC_CONFIG_WEN 1u
#define NVMC_CONFIG_EEN 2u
#define NVMC_ERASEPAGE 0x508u /* ERASEPCR1: erase one page of code region 1 */
#define FICR_CODEPAGESIZE 0x010u
#define FICR_DEVICEID0 0x060u
#define FICR_DEVICEID1 0x064u

/* Cortex-M0 system control space */
#define SCS_SYST_CSR 0xE000E010u
#define SCS_SYST_RVR 0xE000E014u
#define SCS_SYST_CVR 0xE000E018u
#define SCS_NVIC_ISER 0xE000E100u
#define SCS_NVIC_ICER 0xE000E180u
#define SCS_NVIC_ISPR 0xE000E200u
#define SCS_NVIC_ICPR 0xE000E280u
#define SCS_AIRCR 0xE000ED0Cu
#define AIRCR_VECTKEY (0x05FAu << 16)
#define AIRCR_SYSRESETREQ (1u << 2)

#define NRF_HFCLK_HZ 16000000u

static inline void nrf_irq_enable(uint32_t irq)
{
    NRF_REG(SCS_NVIC_ICPR, 0) = 1u << irq;
    NRF_REG(SCS_NVIC_ISER, 0) = 1u << irq;
}

static inline void nrf_irq_disable(uint32_t irq)
{
    NRF_REG(SCS_NVIC_ICER, 0) = 1u << irq;
    NRF_REG(SCS_NVIC_ICPR, 0) = 1u << irq;
}

static inline void nrf_irq_pend(uint32_t irq)
{
    NRF_REG(SCS_NVIC_ISPR, 0) = 1u << irq;
}

#endif
