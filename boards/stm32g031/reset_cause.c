/* SPDX-License-Identifier: Apache-2.0 */
/* RCC_CSR reset flags (RM0444 §5.4) to km_reset_cause_t, most specific cause
 * first. Why this order:
 *
 * - Every internal reset (watchdogs, SYSRESETREQ, option-byte load, low
 *   power, BOR/POR) also pulls NRST low, so PINRSTF is set together with
 *   all of them: it means "the pin" only when it is alone.
 * - PWRRSTF covers both POR/PDR and BOR; the G0 has no separate BOR flag.
 *   What tells them apart here is RAM: a dip below the BOR/PDR threshold
 *   that does not reach 0 V keeps SRAM, a real power-up starts with random
 *   contents. So PWRRSTF with the previous boot's "alive" marker intact is
 *   reported as BROWNOUT, otherwise POWER_ON. A heuristic: a very short cut
 *   that keeps RAM also reads as BROWNOUT, which it is from the servo's
 *   point of view (the supply went away under it). Power outranks
 *   everything: after it nothing else in RAM can be trusted.
 * - A fault reset is a SYSRESETREQ, so the hardware shows SFTRSTF; the
 *   .noinit record written by the fault handler says FAULT. The record wins
 *   over any flag but power: it exists only if the handler ran during this
 *   reset's run (fault.c clears it at every boot), whatever reset followed.
 * - Both watchdogs are WATCHDOG; IWDG outranks SFTRSTF if both were ever
 *   seen together (flags are cleared at every boot, so only a reset during
 *   the few instructions before that clear could leave two).
 * - Low-power (nRST_STOP/STDBY/SHDW option bytes) and option-byte-loader
 *   resets have no name in the contract: OTHER.
 * - No flag at all (a debugger cleared them): POWER_ON, as the contract
 *   says for "no flag the board can read". */
#include "reset_cause.h"

#include "g0_regs.h"

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
