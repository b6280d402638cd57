/* SPDX-License-Identifier: Apache-2.0 */
/* Board-specific entry points of the STM32G031 board beyond hal/: the
 * flash region of the user-data store, the bridge's drive direction. */
#ifndef KM_BOARD_H
#define KM_BOARD_H

#include <stdint.h>

#include "km_hal_flash.h"

/* The user-data store region (the last pages of flash, see stm32g031.ld). */
const km_flash_t *km_board_flash(void);

/* +1 / -1 while driving forward / backward, 0 when coasting or braking. The
 * shunt only sees magnitude; this gives the current its sign. */
int8_t km_board_motor_direction(void);

#endif
