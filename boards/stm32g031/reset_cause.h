/* SPDX-License-Identifier: Apache-2.0 */
/* Reset cause decoding, pure (host-tested by
 * tests/board/test_stm32g031_reset_cause.c). */
#ifndef G0_RESET_CAUSE_H
#define G0_RESET_CAUSE_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_system.h"

/* csr: RCC_CSR before RMVF; fault_recorded: a valid .noinit record;
 * ram_kept: the previous boot's alive marker is intact. */
km_reset_cause_t g0_reset_cause_decode(uint32_t csr, bool fault_recorded, bool ram_kept);

#endif
