/* SPDX-License-Identifier: Apache-2.0 */
/* Reset entry and vector table of the STM32G031 (RM0444 §12.3 table 61); the
 * RAM copies of the table and .ramfunc: docs/flash-busy.md. */
#include <stddef.h>
#include <stdint.h>

#include "fault.h"
#include "g0_core.h"
#include "g0_vectors.h"

extern uint32_t _sbss, _ebss, _estack; /* no .data: stm32g031_sections.ld asserts none */
extern uint32_t _siramfunc, _sramfunc, _eramfunc;
extern uint32_t __ram_vectors[];
extern int main(void);

/* Unexpected vectors: a plain branch to the fault path (IPSR keeps the number). */
__attribute__((naked)) static void prv_default_handler(void)
{
    __asm volatile("ldr r0, =HardFault_Handler\n"
                   "bx  r0                    \n"
                   ".ltorg                    \n");
}

/* Weak: a board file may define them. HardFault_Handler is strong (pulls fault.o). */
#define KM_WEAK_ALIAS __attribute__((weak, alias("prv_default_handler")))
void NMI_Handler(void) KM_WEAK_ALIAS;
void SVC_Handler(void) KM_WEAK_ALIAS;
void PendSV_Handler(void) KM_WEAK_ALIAS;
void SysTick_Handler(void) KM_WEAK_ALIAS;
void TIM2_IRQHandler(void) KM_WEAK_ALIAS;
void USART1_IRQHandler(void) KM_WEAK_ALIAS;

typedef void (*prv_vector_t)(void);

#if KM_G031_SHORT_VECTORS
/* The flash table of a short-header image (docs/update.md §2): only the
 * reset, NMI and HardFault vectors are ever taken from it (the bootloader's
 * table or this one is active until Reset_Handler points VTOR at the RAM
 * table, and no other exception is enabled before that); then the three
 * handlers the drivers use. Reset_Handler builds the 48-entry RAM table
 * from it: every other vector is HardFault_Handler's, where the default
 * handler would branch to with IPSR and LR unchanged (SVCall and PendSV
 * too: only software raises them, and this firmware never does;
 * docs/footprint.md "STM32G031F6"). */
typedef struct {
    uint32_t *initial_sp;
    prv_vector_t core[3]; /* vectors 1..3 */
    prv_vector_t systick, tim2, usart1;
} prv_vector_table_t;

/* A field's word in the table; the RAM table's vectors 0..3 are its first words. */
#define PRV_WORD(field) (offsetof(prv_vector_table_t, field) / sizeof(uint32_t))
#define PRV_VECTOR_HARDFAULT 3u
#define PRV_VECTOR_SYSTICK 15u
#define PRV_VECTOR_IRQ0 16u

__attribute__((section(".isr_vector"), used)) static const prv_vector_table_t s_vectors = {
    .initial_sp = &_estack,
    .core = {Reset_Handler, NMI_Handler, HardFault_Handler},
    .systick = SysTick_Handler,
    .tim2 = TIM2_IRQHandler,
    .usart1 = USART1_IRQHandler,
};

/* The 48 RAM vectors from the short flash table. */
static inline void prv_ram_vectors(void)
{
    const uint32_t *vec = (const uint32_t *)&s_vectors;
    for (uint32_t i = 0u; i < G0_VECTOR_COUNT; i++) {
        __ram_vectors[i] = vec[i < PRV_VECTOR_HARDFAULT ? i : PRV_VECTOR_HARDFAULT];
    }
    __ram_vectors[PRV_VECTOR_SYSTICK] = vec[PRV_WORD(systick)];
    __ram_vectors[PRV_VECTOR_IRQ0 + G0_IRQ_TIM2] = vec[PRV_WORD(tim2)];
    __ram_vectors[PRV_VECTOR_IRQ0 + G0_IRQ_USART1] = vec[PRV_WORD(usart1)];
}
#else
/* Initial stack pointer, then 15 core exceptions, then 32 device IRQs. */
typedef struct {
    uint32_t *initial_sp;
    prv_vector_t core[15];
    prv_vector_t irq[32];
} prv_vector_table_t;

__attribute__((section(".isr_vector"), used)) static const prv_vector_table_t s_vectors = {
    .initial_sp = &_estack,
    .core =
        {
            [0] = Reset_Handler,     /* 1 */
            [1] = NMI_Handler,       /* 2: also flash ECC double errors */
            [2] = HardFault_Handler, /* 3 */
            [3] = prv_default_handler,
            [4] = prv_default_handler,
            [5] = prv_default_handler,
            [6] = prv_default_handler,
            [7] = prv_default_handler,
            [8] = prv_default_handler,
            [9] = prv_default_handler,
            [10] = SVC_Handler, /* 11 */
            [11] = prv_default_handler,
            [12] = prv_default_handler,
            [13] = PendSV_Handler,  /* 14 */
            [14] = SysTick_Handler, /* 15 */
        },
    .irq =
        {
            prv_default_handler, /* 0 */
            prv_default_handler, /* 1 */
            prv_default_handler, /* 2 */
            prv_default_handler, /* 3 */
            prv_default_handler, /* 4 */
            prv_default_handler, /* 5 */
            prv_default_handler, /* 6 */
            prv_default_handler, /* 7 */
            prv_default_handler, /* 8 */
            prv_default_handler, /* 9 */
            prv_default_handler, /* 10 */
            prv_default_handler, /* 11 */
            prv_default_handler, /* 12 */
            prv_default_handler, /* 13 */
            prv_default_handler, /* 14 */
            TIM2_IRQHandler,     /* 15 */
            prv_default_handler, /* 16 */
            prv_default_handler, /* 17 */
            prv_default_handler, /* 18 */
            prv_default_handler, /* 19 */
            prv_default_handler, /* 20 */
            prv_default_handler, /* 21 */
            prv_default_handler, /* 22 */
            prv_default_handler, /* 23 */
            prv_default_handler, /* 24 */
            prv_default_handler, /* 25 */
            prv_default_handler, /* 26 */
            USART1_IRQHandler,   /* 27 */
            prv_default_handler, /* 28 */
            prv_default_handler, /* 29 */
            prv_default_handler, /* 30 */
            prv_default_handler, /* 31 */
        },
};

/* The RAM vectors: a copy of the flash table. */
static inline void prv_ram_vectors(void)
{
    const uint32_t *vec = (const uint32_t *)&s_vectors;
    for (uint32_t i = 0u; i < sizeof s_vectors / sizeof(uint32_t); i++) {
        __ram_vectors[i] = vec[i];
    }
}
#endif
_Static_assert(sizeof s_vectors <= G0_VECTOR_COUNT * sizeof(uint32_t), "the flash table fits the RAM one");

/* RAM vectors and .ramfunc, VTOR, .bss, stack paint, reset cause, main(). */
void Reset_Handler(void)
{
    prv_ram_vectors();
    uint32_t *src = &_siramfunc;
    for (uint32_t *dst = &_sramfunc; dst < &_eramfunc;) {
        *dst++ = *src++;
    }
    /* DSB completes the copies, ISB refetches after the VTOR write. */
    __asm volatile("dsb" ::: "memory");
    SCB_VTOR = (uint32_t)(uintptr_t)__ram_vectors;
    __asm volatile("dsb\n\tisb" ::: "memory");
    for (uint32_t *dst = &_sbss; dst < &_ebss;) {
        *dst++ = 0u;
    }
    g0_stack_paint();
    g0_reset_capture();
    (void)main();
    for (;;) {
    }
}
