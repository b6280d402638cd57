/* The application's half of the handshake with the bootloader (docs/update.md
 * §3): 0x78 ENTER leaves the "stay in update mode" request in the shared
 * RAM words; the app then restarts. Linked only into application images
 * built for the bootloader's region. */
#include <stdbool.h>
#include <stdint.h>

#include "boot_layout.h"
#include "km_app.h"
#include "km_boot_board.h"

bool km_board_boot_request(void)
{
    volatile km_boot_shared_t *sh = (volatile km_boot_shared_t *)(uintptr_t)BOOT_SHARED_ADDR;
    if (sh->check != ~sh->boot_version) {
        return false; /* not started by a bootloader */
    }
    sh->request = KM_BOOT_REQUEST_MAGIC;
    return true;
}
