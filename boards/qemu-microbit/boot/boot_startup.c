/* The bootloader's vector table and reset for the nRF51 (docs/update.md
 * §5). The Cortex-M0 has no VTOR: the core always vectors through this
 * table at address 0, so every entry but the initial SP and the reset
 * vector is one forwarding stub. While the application runs (its magic in
 * the shared RAM words) the stub loads the handler from the application's
 * table (the region start + 0x100, indexed by IPSR) and branches to it
 * with LR untouched, so the exception return and the stacked frame are the
 * application's own, as if the core had vectored there: six instructions
 * more per exception. Otherwise (the bootloader runs with no interrupt
 * enabled) it is a fault: reset. */
#include <stdint.h>

#include "boot_layout.h"

extern uint32_t __data_load[];
extern uint32_t __data_start[];
extern uint32_t __data_end[];
extern uint32_t __bss_start[];
extern uint32_t __bss_end[];
extern uint32_t __stack_top[];

int main(void);
void km_boot_reset_handler(void);
void km_boot_forward(void);

#define PRV_STR2(x) #x
#define PRV_STR(x) PRV_STR2(x)

__attribute__((naked)) void km_boot_forward(void)
{
    __asm__ volatile(
        ".syntax unified                   \n"
        "ldr  r0, =" PRV_STR(BOOT_APP_RUNNING_ADDR) "\n"
        "ldr  r0, [r0]                     \n"
        "ldr  r1, =" PRV_STR(BOOT_APP_MAGIC_WORD) "\n"
        "cmp  r0, r1                       \n"
        "bne  1f                           \n"
        "mrs  r0, ipsr                     \n"
        "lsls r0, r0, #2                   \n"
        "ldr  r1, =" PRV_STR(BOOT_APP_VECTORS) "\n"
        "ldr  r0, [r1, r0]                 \n"
        "bx   r0                           \n"
        "1:                                \n"
        "ldr  r0, =" PRV_STR(BOOT_AIRCR) "\n"
        "ldr  r1, =" PRV_STR(BOOT_AIRCR_RESET) "\n"
        "dsb                               \n"
        "str  r1, [r0]                     \n"
        "dsb                               \n"
        "2: b 2b                           \n"
        ".ltorg                            \n");
}

typedef void (*km_vector_t)(void);

/* 16 core entries + 32 nRF51 interrupts, all but two forwarded. */
__attribute__((section(".isr_vector"), used)) const km_vector_t km_vectors[48] = {
    (km_vector_t)(uintptr_t)__stack_top, km_boot_reset_handler,
    km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward,
    km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward,
    km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward,
    km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward,
    km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward,
    km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward,
    km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward,
    km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward,
    km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward, km_boot_forward,
    km_boot_forward,
};

void km_boot_reset_handler(void)
{
    const uint32_t *src = __data_load;
    for (uint32_t *dst = __data_start; dst < __data_end; dst++) {
        *dst = *src++;
    }
    for (uint32_t *dst = __bss_start; dst < __bss_end; dst++) {
        *dst = 0u;
    }
    (void)main();
    for (;;) {
    }
}
