/* SPDX-License-Identifier: Apache-2.0 */
/* RCC_CSR reset flags (RM0444 §5.4) to km_reset_cause_t, most specific
 * first; the order and the brown-out heuristic: README.md "Faults, reset
 * cause, stack". */
#include "reset_cause.h"

#include "g0_regs.h"

/* The reset cause from RCC_CSR, the fault record and the RAM marker. */
km_reset_cause_t g0_reset_cause_decode(uint32_t csr, bool fault_recorded, bool ram_kept)
{
    if ((csr & RCC_CSR_PWRRSTF) != 0u) {
        return ram_kept ? KM_RESET_BROWNOUT : KM_RESET_POWER_ON;
    }
    if (fault_recorded) {
        return KM_RESET_FAULT;
    }
    if ((csr & (RCC_CSR_IWDGRSTF | RCC_CSR_WWDGRSTF)) != 0u) {
        return KM_RESET_WATCHDOG;
    }
    if ((csr & RCC_CSR_SFTRSTF) != 0u) {
        return KM_RESET_SOFTWARE;
    }
    if ((csr & (RCC_CSR_LPWRRSTF | RCC_CSR_OBLRSTF)) != 0u) {
        return KM_RESET_OTHER;
    }
    if ((csr & RCC_CSR_PINRSTF) != 0u) {
        return KM_RESET_PIN;
    }
    return KM_RESET_POWER_ON;
}
