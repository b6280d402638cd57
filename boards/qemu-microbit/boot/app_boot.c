/* SPDX-License-Identifier: Apache-2.0 */
/* The application's half of the handshake with the bootloader (docs/update.md
 * §3, §3a): 0x78 ENTER leaves the "stay in update mode" request in the
 * shared RAM words (the app then restarts), and the confirmation of a good
 * start stops the bootloader's trial timer and says so in the same words.
 * Linked only into application images built for the bootloader's region. */
#include <stdbool.h>
#include <stdint.h>

#include "boot_layout.h"
#include "km_app.h"
#include "km_boot_board.h"
#include "nrf51_regs.h"

/* The words shared with the bootloader (km_boot_trial.h). */
static volatile km_boot_shared_t *prv_shared(void)
{
    return (volatile km_boot_shared_t *)(uintptr_t)BOOT_SHARED_ADDR;
}

/* 0x78 ENTER: leave the request, ID and baud for the bootloader (km_app.h). */
bool km_board_boot_request(uint8_t id, uint32_t baud)
{
    if (!km_boot_started_by_loader(prv_shared())) {
        return false; /* not started by a bootloader */
    }
    km_boot_handoff_set(prv_shared(), id, baud);
    prv_shared()->request = KM_BOOT_REQUEST_MAGIC;
    return true;
}

/* The timer first: its interrupt, taken before the word below is written,
 * resets (the trial failed); after it, it can no longer fire, so TIMER2
 * and its vector are this application's from now on. */
void km_board_boot_confirm(void)
{
    if (!km_boot_started_by_loader(prv_shared())) {
        return;
    }
    nrf_irq_disable(BOOT_TRIAL_IRQ);
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_TASKS_STOP) = 1u;
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_INTENCLR) = TIMER_INT_COMPARE(0);
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_EVENTS_COMPARE(0)) = 0u;
    nrf_irq_disable(BOOT_TRIAL_IRQ); /* clears a pend the event left meanwhile */
    km_boot_confirm(prv_shared());
}
