/* SPDX-License-Identifier: Apache-2.0 */
/* Application images that pass every check of the bootloader (header,
 * CRC-32, initial SP, reset vector inside the image) but never serve the
 * bus (docs/update.md §3a, tests/qemu/update_trial.py): built with
 * KM_BAD_HANG the reset vector is `b .`, with KM_BAD_CRASH it is an
 * undefined instruction (`udf #0`, a HardFault at once). Every other vector
 * points at the same code, so the image's own fault handler hangs or
 * faults again: nothing of it helps the servo back. Linked for the
 * application region with nrf51822_app.ld, made an update image by
 * tools/gen/make-image. Never flashed anywhere but in that test. */
#include <stdint.h>

extern uint32_t __stack_top[];

void Reset_Handler(void);

__attribute__((naked)) void Reset_Handler(void)
{
#if defined(KM_BAD_HANG)
    __asm__ volatile("1: b 1b");
#elif defined(KM_BAD_CRASH)
    __asm__ volatile("udf #0");
#else
#error "KM_BAD_HANG or KM_BAD_CRASH"
#endif
}

typedef void (*km_vector_t)(void);

#define PRV_R Reset_Handler

__attribute__((section(".isr_vector"), used)) const km_vector_t km_vectors[48] = {
    (km_vector_t)(uintptr_t)__stack_top,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
    PRV_R,
};
