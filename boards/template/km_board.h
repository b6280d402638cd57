/* SPDX-License-Identifier: Apache-2.0 */
/* Template: what a board offers beyond the hal contracts. Every board gives
 * the store its flash region this way. */
#ifndef KM_BOARD_H
#define KM_BOARD_H

#include "km_hal_flash.h"

/* The flash region of the user-data store. */
const km_flash_t *km_board_flash(void);

#endif
