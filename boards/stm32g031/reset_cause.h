/* SPDX-License-Identifier: Apache-2.0 */
/* The pure part of the STM32G031's reset cause: RCC_CSR flags plus what the
 * board's .noinit RAM says, mapped to the hal's km_reset_cause_t. No
 * register access here, so tests/board/test_stm32g031_reset_cause.c runs it
 * on the host; fault.c reads the hardware and calls it once at boot. */
#ifndef G0_RESET_CAUSE_H
#define G0_RESET_CAUSE_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_system.h"

/* csr: RCC_CSR as read before RMVF. fault_recorded: the fault handler left a
 * valid record in .noinit RAM before it reset. ram_kept: the .noinit "alive"
 * marker of the previous boot is intact, i.e. RAM kept its contents. */
km_reset_cause_t g0_reset_cause_decode(uint32_t csr, bool fault_recorded, bool ram_kept);

#endif
