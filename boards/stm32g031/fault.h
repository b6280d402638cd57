/* SPDX-License-Identifier: Apache-2.0 */
/* Fault handling, reset cause and stack guard of the STM32G031 board
 * (fault.c): what startup.c and system.c call. The README's "Faults, reset
 * cause, stack" section explains the whole scheme. */
#ifndef G0_FAULT_H
#define G0_FAULT_H

#include <stdbool.h>
#include <stdint.h>

/* Recorded instead of an exception number when the stack guard band was
 * found overwritten (no exception was taken: SysTick noticed it). */
#define G0_FAULT_STACK_GUARD 0x100u

/* Reset_Handler, once, after .data/.bss are set up and before main():
 * fill the stack below the reset handler's own frame with a pattern (the
 * guard band and a high-water mark a debugger can read)... */
void g0_stack_paint(void);
/* ...then read and clear RCC_CSR and the .noinit fault record, and keep the
 * decoded cause for km_hal_reset_cause(). Before main, so the flags of this
 * reset are cleared before anything could cause the next one. */
void g0_reset_capture(void);

/* False once anything wrote into the guard band at the bottom of the stack:
 * the stack came within KM_STACK_GUARD bytes (a multiple of 32, at least
 * 32) of the end of SRAM. Each call checks the next quarter of a 128-byte
 * band, so four calls cover it. */
bool g0_stack_guard_intact(void);

/* Bridge free, record {kind, pc, lr} in .noinit, SYSRESETREQ. Moves SP to
 * the top of the stack first (the old one may be what ran out), so it is
 * safe to call with almost no stack left. */
_Noreturn void g0_fault_stop(uint32_t kind, uint32_t pc, uint32_t lr);

#endif
