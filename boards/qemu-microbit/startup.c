/* SPDX-License-Identifier: Apache-2.0 */
/* Startup for the nRF51822 (Cortex-M0): the vector table, the reset handler
 * that lays out RAM for C (.data copied from flash, .bss zeroed) and
 * captures the reset cause (system.c), and the default handler every unused
 * interrupt falls into, which takes the fault path (system.c's
 * HardFault_Handler: record, reset at once). */
#include <stdint.h>

/* Linker script symbols: addresses only, never read as objects. */
extern uint32_t __data_load[];
extern uint32_t __data_start[];
extern uint32_t __data_end[];
extern uint32_t __bss_start[];
extern uint32_t __bss_end[];
extern uint32_t __stack_top[];

int main(void);
void Reset_Handler(void);
void Default_Handler(void);
void HardFault_Handler(void);      /* system.c; not weak: it pulls system.o in */
void km_board_reset_capture(void); /* system.c */

/* Weak so a driver defines the real one simply by naming it. */
#define KM_WEAK_HANDLER(name) void name(void) __attribute__((weak, alias("Default_Handler")))
KM_WEAK_HANDLER(NMI_Handler);
KM_WEAK_HANDLER(SVC_Handler);
KM_WEAK_HANDLER(PendSV_Handler);
KM_WEAK_HANDLER(SysTick_Handler);
KM_WEAK_HANDLER(POWER_CLOCK_IRQHandler);
KM_WEAK_HANDLER(RADIO_IRQHandler);
KM_WEAK_HANDLER(UART0_IRQHandler);
KM_WEAK_HANDLER(SPI0_TWI0_IRQHandler);
KM_WEAK_HANDLER(SPI1_TWI1_IRQHandler);
KM_WEAK_HANDLER(GPIOTE_IRQHandler);
KM_WEAK_HANDLER(ADC_IRQHandler);
KM_WEAK_HANDLER(TIMER0_IRQHandler);
KM_WEAK_HANDLER(TIMER1_IRQHandler);
KM_WEAK_HANDLER(TIMER2_IRQHandler);
KM_WEAK_HANDLER(RTC0_IRQHandler);
KM_WEAK_HANDLER(TEMP_IRQHandler);
KM_WEAK_HANDLER(RNG_IRQHandler);
KM_WEAK_HANDLER(ECB_IRQHandler);
KM_WEAK_HANDLER(CCM_AAR_IRQHandler);
KM_WEAK_HANDLER(WDT_IRQHandler);
KM_WEAK_HANDLER(RTC1_IRQHandler);
KM_WEAK_HANDLER(QDEC_IRQHandler);
KM_WEAK_HANDLER(LPCOMP_IRQHandler);
KM_WEAK_HANDLER(SWI0_IRQHandler);
KM_WEAK_HANDLER(SWI1_IRQHandler);
KM_WEAK_HANDLER(SWI2_IRQHandler);
KM_WEAK_HANDLER(SWI3_IRQHandler);
KM_WEAK_HANDLER(SWI4_IRQHandler);
KM_WEAK_HANDLER(SWI5_IRQHandler);

typedef void (*km_vector_t)(void);

/* 16 core entries + 32 nRF51 interrupts; the linker keeps it at address 0. */
__attribute__((section(".isr_vector"), used)) const km_vector_t km_vectors[48] = {
    (km_vector_t)(uintptr_t)__stack_top,
    Reset_Handler,
    NMI_Handler,
    HardFault_Handler,
    0,
    0,
    0,
    0,
    0,
    0,
    0,
    SVC_Handler,
    0,
    0,
    PendSV_Handler,
    SysTick_Handler,
    POWER_CLOCK_IRQHandler, /* 0 */
    RADIO_IRQHandler,
    UART0_IRQHandler,
    SPI0_TWI0_IRQHandler,
    SPI1_TWI1_IRQHandler,
    0,
    GPIOTE_IRQHandler,
    ADC_IRQHandler,
    TIMER0_IRQHandler, /* 8 */
    TIMER1_IRQHandler,
    TIMER2_IRQHandler,
    RTC0_IRQHandler,
    TEMP_IRQHandler,
    RNG_IRQHandler,
    ECB_IRQHandler,
    CCM_AAR_IRQHandler,
    WDT_IRQHandler, /* 16 */
    RTC1_IRQHandler,
    QDEC_IRQHandler,
    LPCOMP_IRQHandler,
    SWI0_IRQHandler,
    SWI1_IRQHandler,
    SWI2_IRQHandler,
    SWI3_IRQHandler,
    SWI4_IRQHandler, /* 24 */
    SWI5_IRQHandler,
    0,
    0,
    0,
    0,
    0,
    0,
};

void Reset_Handler(void)
{
    /* Word loops on purpose: the linker script aligns both sections to 4. */
    const uint32_t *src = __data_load;
    for (uint32_t *dst = __data_start; dst < __data_end; dst++) {
        *dst = *src++;
    }
    for (uint32_t *dst = __bss_start; dst < __bss_end; dst++) {
        *dst = 0u;
    }
    km_board_reset_capture();
    (void)main();
    /* main never returns in firmware; a test image that does just parks. */
    for (;;) {
    }
}

/* An unexpected interrupt: handled as a fault (record, reset at once).
 * Parking would hang for ever in QEMU, which does not model the watchdog.
 * A plain branch that touches no stack; the stacked PC still says where. */
__attribute__((naked)) void Default_Handler(void)
{
    __asm__ volatile("ldr r0, =HardFault_Handler\n"
                     "bx  r0                    \n");
}
