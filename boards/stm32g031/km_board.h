/* SPDX-License-Identifier: Apache-2.0 */
/* STM32G031 entry points beyond hal/. */
#ifndef KM_BOARD_H
#define KM_BOARD_H

#include <stdint.h>

#include "km_hal_flash.h"

/* The user-data store's flash (stm32g031.ld). */
const km_flash_t *km_board_flash(void);

/* +1 / -1 driving forward / backward, else 0: the current's sign. */
int8_t km_board_motor_direction(void);

#endif
