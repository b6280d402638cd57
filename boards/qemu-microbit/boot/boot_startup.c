/* SPDX-License-Identifier: Apache-2.0 */
/* The bootloader's vector table and reset for the nRF51 (docs/update.md
 * §5). The Cortex-M0 has no VTOR: the core always vectors through this
 * table at address 0, so every entry but the initial SP and the reset
 * vector is one forwarding stub. While the application runs (its magic in
 * the shared RAM words) the stub loads the handler from the application's
 * table (the region start + 0x100, indexed by IPSR) and branches to it
 * with LR untouched, so the exception return and the stacked frame are the
 * application's own, as if the core had vectored there: six instructions
 * more per exception. Otherwise (the bootloader runs with no interrupt
 * enabled) it is a fault: reset.
 *
 * Two entries are the trial's (docs/update.md §3a): HardFault and the
 * trial timer's interrupt (TIMER2) go to km_boot_trial, which resets
 * while the application has not confirmed its start (the start was
 * counted before the jump), and forwards like every other entry once it
 * has. So an image that faults before it confirms is reset even if its
 * own HardFault handler is garbage, and one that hangs is reset by the
 * timer after 2 s. */
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
void km_boot_trial(void);

#define PRV_STR2(x) #x
#define PRV_STR(x) PRV_STR2(x)

__attribute__((naked)) void km_boot_forward(void)
{
    __asm__ volatile(
        ".syntax unified                   \n"
        "ldr  r0, =" PRV_STR(
            BOOT_APP_RUNNING_ADDR) "\n"
                                   "ldr  r0, [r0]                     \n"
                                   "ldr  r1, =" PRV_STR(
                                       BOOT_APP_MAGIC_WORD) "\n"
                                                            "cmp  r0, r1                       \n"
                                                            "bne  1f                           \n"
                                                            "mrs  r0, ipsr                     \n"
                                                            "lsls r0, r0, #2                   \n"
                                                            "ldr  r1, =" PRV_STR(
                                                                BOOT_APP_VECTORS) "\n"
                                                                                  "ldr  r0, [r1, r0]         "
                                                                                  "        \n"
                                                                                  "bx   r0                   "
                                                                                  "        \n"
                                                                                  "1:                        "
                                                                                  "        \n"
                                                                                  "ldr  r0, =" PRV_STR(
                                                                                      BOOT_AIRCR) "\n"
                                                                                                  "ldr  r1, "
                                                                                                  "=" PRV_STR(
                                                                                                      BOOT_AIRCR_RESET) "\n"
                                                                                                                        "dsb                               \n"
                                                                                                                        "str  r1, [r0]                     \n"
                                                                                                                        "dsb                               \n"
                                                                                                                        "2: b 2b                           \n"
                                                                                                                        ".ltorg                            \n");
}

/* The trial's entries: reset unless the application confirmed its start
 * (the confirmed word holds its magic), else forward. r0-r3 are stacked. */
__attribute__((naked)) void km_boot_trial(void)
{
    __asm__ volatile(
        ".syntax unified                   \n"
        "ldr  r0, =" PRV_STR(
            BOOT_CONFIRMED_ADDR) "\n"
                                 "ldr  r0, [r0]                     \n"
                                 "ldr  r1, =" PRV_STR(
                                     BOOT_CONFIRMED_WORD) "\n"
                                                          "cmp  r0, r1                       \n"
                                                          "bne  1f                           \n"
                                                          "ldr  r0, =km_boot_forward         \n"
                                                          "bx   r0                           \n"
                                                          "1:                                \n"
                                                          "ldr  r0, =" PRV_STR(
                                                              BOOT_AIRCR) "\n"
                                                                          "ldr  r1, =" PRV_STR(
                                                                              BOOT_AIRCR_RESET) "\n"
                                                                                                "dsb         "
                                                                                                "            "
                                                                                                "          \n"
                                                                                                "str  r1, "
                                                                                                "[r0]        "
                                                                                                "            "
                                                                                                " \n"
                                                                                                "dsb         "
                                                                                                "            "
                                                                                                "          \n"
                                                                                                "2: b 2b     "
                                                                                                "            "
                                                                                                "          \n"
                                                                                                ".ltorg      "
                                                                                                "            "
                                                                                                "          "
                                                                                                "\n");
}

typedef void (*km_vector_t)(void);

#define PRV_F km_boot_forward
#define PRV_T km_boot_trial

/* 16 core entries + 32 nRF51 interrupts: the initial SP, the reset, the
 * trial's two (HardFault, IRQ BOOT_TRIAL_IRQ = TIMER2), the rest forwarded. */
__attribute__((section(".isr_vector"), used)) const km_vector_t km_vectors[48] = {
    (km_vector_t)(uintptr_t)__stack_top,
    km_boot_reset_handler,
    PRV_F,
    PRV_T,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    /* IRQ 0-15 */
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_T,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    /* IRQ 16-31 */
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
    PRV_F,
};
_Static_assert(BOOT_TRIAL_IRQ == 10, "km_vectors puts km_boot_trial at IRQ 10");

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
