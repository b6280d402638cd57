/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: the user-data flash region in a file (see hs_flash.c). */
#ifndef HS_FLASH_H
#define HS_FLASH_H

#include <stdbool.h>

#include "km_hal_flash.h"

/* Opens (creating erased) the flash file and fills `flash`. */
bool hs_flash_open(const char *path, km_flash_t *flash);

#endif
