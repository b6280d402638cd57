/* SPDX-License-Identifier: Apache-2.0 */
/* A read-only look at a few stored values (the bootloader's ID and baud, docs/update.md §3). */
#ifndef KM_STORE_PEEK_H
#define KM_STORE_PEEK_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"

/* True if the mount would load (LOADED or MIGRATED): values[] then holds the stored values; n <= 4. */
bool km_store_peek(const km_flash_t *f, uint16_t version, const uint8_t *keys, uint32_t n, uint32_t *values);

#endif
