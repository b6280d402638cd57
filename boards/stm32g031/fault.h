/* SPDX-License-Identifier: Apache-2.0 */
/* Fault path, reset cause and stack guard (fault.c); README.md "Faults,
 * reset cause, stack". */
#ifndef G0_FAULT_H
#define G0_FAULT_H

#include <stdbool.h>
#include <stdint.h>

/* Record kind when SysTick found the stack guard band overwritten. */
#define G0_FAULT_STACK_GUARD 0x100u

/* Reset_Handler, before main(): paint the stack (guard band, high-water mark)... */
void g0_stack_paint(void);
/* ...then read and clear RCC_CSR and the fault record, keep the cause. */
void g0_reset_capture(void);

/* False once the guard band (KM_STACK_GUARD bytes, a multiple of 32) was
 * written; each call checks the next four words (fault.c). */
bool g0_stack_guard_intact(void);

/* Bridge free, record {kind, pc, lr}, SYSRESETREQ; on a fresh stack. */
_Noreturn void g0_fault_stop(uint32_t kind, uint32_t pc, uint32_t lr);

#endif
