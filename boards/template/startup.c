/* SPDX-License-Identifier: Apache-2.0 */
/* Template: the vector table and the reset handler of a Cortex-M; add the MCU's
 * device interrupts after the 16 core entries (docs/architecture.md "Filling in
 * the template"). */
#include <stdint.h>

/* Linker script symbols (board.ld): addresses only, never read as objects. */
extern uint32_t __data_load[];
extern uint32_t __data_start[];
extern uint32_t __data_end[];
extern uint32_t __bss_start[];
extern uint32_t __bss_end[];
extern uint32_t __stack_top[];

int main(void);
void Reset_Handler(void);
void Default_Handler(void);

/* Weak so a driver defines the real one simply by naming it. */
#define KM_WEAK_HANDLER(name) void name(void) __attribute__((weak, alias("Default_Handler")))
KM_WEAK_HANDLER(NMI_Handler);
KM_WEAK_HANDLER(HardFault_Handler);
KM_WEAK_HANDLER(SVC_Handler);
KM_WEAK_HANDLER(PendSV_Handler);
KM_WEAK_HANDLER(SysTick_Handler);

typedef void (*km_vector_t)(void);

/* The 16 core entries; the linker keeps the table at the start of flash. */
__attribute__((section(".isr_vector"), used)) const km_vector_t km_vectors[16] = {
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
};

/* Copy .data, zero .bss, run main(). */
void Reset_Handler(void)
{
    /* Word loops: the linker script aligns both sections to 4. Each pair of
     * symbols bounds one object the linker made: cppcheck's comparePointers. */
    const uint32_t *src = __data_load;
    // cppcheck-suppress comparePointers
    for (uint32_t *dst = __data_start; dst < __data_end; dst++) {
        *dst = *src++;
    }
    // cppcheck-suppress comparePointers
    for (uint32_t *dst = __bss_start; dst < __bss_end; dst++) {
        *dst = 0u;
    }
    (void)main();
    for (;;) {
    }
}

/* An interrupt nothing handles: park (replace with your fault path). */
void Default_Handler(void)
{
    for (;;) {
    }
}
