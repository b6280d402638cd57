/* SPDX-License-Identifier: Apache-2.0 */
/* The application's half of the handshake with the bootloader (docs/update.md
 * §3, §3a): 0x78 ENTER leaves the "stay in update mode" request in the
 * shared RAM words (the app then restarts), and the confirmation of a good
 * start says so in the same words. Linked only into application images
 * built for the bootloader's region. */
#include <stdbool.h>
#include <stdint.h>

#include "boot_layout.h"
#include "km_app.h"
#include "km_boot_board.h"

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

/* Nothing to stop on this board: its trial is the bootloader's IWDG, which
 * km_hal_watchdog_start took over. */
void km_board_boot_confirm(void)
{
    if (km_boot_started_by_loader(prv_shared())) {
        km_boot_confirm(prv_shared());
    }
}
