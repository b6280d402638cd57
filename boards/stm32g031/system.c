/* SPDX-License-Identifier: Apache-2.0 */
/* km_hal_system for the STM32G031: clock, reset, IWDG, PRIMASK lock, entropy,
 * WFI idle and sleep-on-exit with a 1 kHz SysTick wake-up (README.md "Drivers"). */
#include "km_cortex_m.h"
#include "km_hal_system.h"

#include "km_hal_time.h"

#include "board_clock.h"
#include "fault.h"
#include "g0_regs.h"
#include "g0_vectors.h"

/* HSI16 -> PLL -> SYSCLK 64 MHz (RM0444 §5.2.3, §5.4.4); 2 flash wait states
 * (§3.3.4 table 12) set and read back before the switch. */
static void prv_clock_64mhz(void)
{
    FLASH_ACR = (FLASH_ACR & ~FLASH_ACR_LATENCY_MASK) | 2u | FLASH_ACR_PRFTEN | FLASH_ACR_ICEN;
    while ((FLASH_ACR & FLASH_ACR_LATENCY_MASK) != 2u) {
    }

    RCC_CR |= RCC_CR_HSION;
    while ((RCC_CR & RCC_CR_HSIRDY) == 0u) {
    }
    RCC_PLLCFGR = RCC_PLLCFGR_SRC_HSI16 | (0u << RCC_PLLCFGR_M_SHIFT) | (8u << RCC_PLLCFGR_N_SHIFT) |
                  (1u << RCC_PLLCFGR_R_SHIFT) | RCC_PLLCFGR_REN;
    RCC_CR |= RCC_CR_PLLON;
    while ((RCC_CR & RCC_CR_PLLRDY) == 0u) {
    }
    RCC_CFGR = (RCC_CFGR & ~RCC_CFGR_SW_MASK) | RCC_CFGR_SW_PLLRCLK;
    while (((RCC_CFGR >> RCC_CFGR_SWS_SHIFT) & 7u) != RCC_CFGR_SW_PLLRCLK) {
    }
}

#define WAKE_HZ 1000u

/* Clock, GPIO clocks and the 1 kHz SysTick wake-up. */
void km_hal_system_init(void)
{
    prv_clock_64mhz();
    RCC_IOPENR |= RCC_IOPENR_GPIOA | RCC_IOPENR_GPIOB;
    /* Lowest priority: never delays a bus byte's time stamp. */
    SCB_SHPR3 = (SCB_SHPR3 & 0x00FFFFFFu) | (0xC0u << 24);
    SYST_RVR = BOARD_SYSCLK_HZ / WAKE_HZ - 1u;
    SYST_CVR = 0u;
    SYST_CSR = SYST_CSR_CLKSOURCE | SYST_CSR_TICKINT | SYST_CSR_ENABLE;
}

/* Wakes the main loop (km_hal_sleep's 1 ms) and checks the stack guard; in
 * RAM (runs during erases). */
G0_RAMFUNC(SysTick_Handler) void SysTick_Handler(void)
{
    if (!g0_stack_guard_intact()) {
        g0_fault_stop(G0_FAULT_STACK_GUARD, 0u, 0u);
    }
    km_cortex_wake();
}

/* SYSRESETREQ. */
_Noreturn void km_hal_system_reset(void)
{
    __asm volatile("dsb" ::: "memory");
    SCB_AIRCR = SCB_AIRCR_VECTKEY | SCB_AIRCR_SYSRESETREQ;
    __asm volatile("dsb" ::: "memory");
    for (;;) {
    }
}

/* IWDG (RM0444 §27.3): timeout = (RLR+1) * 4 * 2^PR / 32 kHz, smallest PR. */
void km_hal_watchdog_start(uint32_t timeout_ms)
{
    uint32_t pr = 0u;
    uint32_t ticks = 0u;
    for (; pr <= 6u; pr++) {
        ticks = (timeout_ms * 32u) / (4u << pr);
        if (ticks <= 4096u) {
            break;
        }
    }
    if (pr > 6u) {
        pr = 6u;
        ticks = 4096u;
    }
    if (ticks == 0u) {
        ticks = 1u;
    }
    IWDG_KR = IWDG_KEY_START; /* §27.3.2 */
    IWDG_KR = IWDG_KEY_UNLOCK;
    IWDG_PR = pr;
    IWDG_RLR = ticks - 1u;
    while (IWDG_SR != 0u) { /* PVU/RVU */
    }
    IWDG_KR = IWDG_KEY_KICK;
}

/* Reloads the IWDG. */
void km_hal_watchdog_kick(void)
{
    IWDG_KR = IWDG_KEY_KICK;
}

/* Masks interrupts, returns the previous state. */
uint32_t km_hal_irq_lock(void)
{
    return km_cortex_irq_lock();
}

/* Restores the interrupt mask. */
void km_hal_irq_restore(uint32_t state)
{
    km_cortex_irq_restore(state);
}

/* Multiply-xorshift finaliser: every input bit reaches every output bit. */
static uint32_t prv_mix(uint32_t h)
{
    h ^= h >> 16;
    h *= 0x7FEB352Du;
    h ^= h >> 15;
    h *= 0x846CA68Bu;
    h ^= h >> 16;
    return h;
}

/* Unique ID (RM0444 §40.1) and the µs counter, mixed. */
uint32_t km_hal_entropy(void)
{
    const volatile uint32_t *uid = (const volatile uint32_t *)(uintptr_t)UID_BASE_R;
    uint32_t h = 0x9E3779B9u;
    for (uint32_t i = 0u; i < 3u; i++) {
        h = prv_mix(h ^ uid[i]);
    }
    return prv_mix(h ^ km_hal_time_now());
}

/* WFI. */
void km_hal_idle(void)
{
    km_cortex_wait_for_interrupt();
}

/* Sleep-on-exit until a wake (docs/benchmarks.md "Per byte"). */
void km_hal_sleep(uint32_t state)
{
    km_cortex_sleep_until_wake(state);
}

/* In RAM: the receive and timer interrupts call it during erases. */
G0_RAMFUNC(km_hal_wake) void km_hal_wake(void)
{
    km_cortex_wake();
}
