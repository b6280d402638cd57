/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: the board-provided pieces the application asks for (its flash
 * region); the product and the plant-backed sensors come from sim-common. */
#include "km_app.h"

static km_flash_t s_flash;

void hs_board_set_flash(const km_flash_t *flash);

void hs_board_set_flash(const km_flash_t *flash)
{
    s_flash = *flash;
}

const km_flash_t *km_board_flash(void)
{
    return &s_flash;
}
