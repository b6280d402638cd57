/* SPDX-License-Identifier: Apache-2.0 */
/* The STM32G031 bootloader's vector table and reset (docs/update.md §5).
 * The bootloader polls and enables no interrupt: its table has the reset,
 * the NMI (a double ECC error on a flash read, which boot_board.c's read
 * turns into "this cell cannot be trusted") and every other vector on the
 * reset path. The application gets its own table through VTOR. */
#include <stdint.h>

#include "g0_core.h"
#include "g0_regs.h"

extern uint32_t __bss_start[];
extern uint32_t __bss_end[];
extern uint32_t __stack_top[];

int main(void);
void km_boot_reset_handler(void);
void km_boot_nmi(void);
void km_boot_unexpected(void);

volatile uint32_t km_boot_ecc_errors;

void km_boot_nmi(void)
{
    if ((FLASH_ECCR & FLASH_ECCR_ECCD) != 0u) {
        FLASH_ECCR = FLASH_ECCR_ECCD; /* rc_w1 */
        km_boot_ecc_errors++;
        return;
    }
    km_boot_unexpected();
}

void km_boot_unexpected(void)
{
    SCB_AIRCR = 0x05FA0004u; /* VECTKEY | SYSRESETREQ: start over, reachable again */
    for (;;) {
    }
}

typedef void (*km_vector_t)(void);

/* SP, reset, NMI, HardFault (reset): the four entries an exception can
 * reach. SVCall, PendSV and SysTick (entries 11, 14, 15) are raised only
 * by software (an SVC instruction, ICSR, a started SysTick), which the
 * bootloader never does, so its table ends here and code follows
 * (48 B of the 4 KiB, docs/footprint.md). */
__attribute__((section(".isr_vector"), used)) const km_vector_t km_vectors[4] = {
    (km_vector_t)(uintptr_t)__stack_top,
    km_boot_reset_handler,
    km_boot_nmi,
    km_boot_unexpected,
};

/* Zeroes .bss and runs main. The bootloader has no initialised data
 * (boot.ld asserts .data empty), so nothing is copied. */
void km_boot_reset_handler(void)
{
    for (uint32_t *dst = __bss_start; dst < __bss_end; dst++) {
        *dst = 0u;
    }
    (void)main();
    km_boot_unexpected();
}
