/* SPDX-License-Identifier: Apache-2.0 */
/* A read-only look at a few stored values (the bootloader's ID and baud,
 * docs/update.md §3): what km_store_mount() would load for a schema of just
 * those keys, without the mount's page bookkeeping (suspect pages, the
 * first commit's target, the blank/invalid distinction), which only a
 * session that commits needs. tests/unit/store/test_store_peek.c checks it
 * against km_store_mount() on stores left by random sessions and power
 * cuts. */
#ifndef KM_STORE_PEEK_H
#define KM_STORE_PEEK_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"

/* values[i] holds key keys[i]'s default on entry. True if the mount would
 * return LOADED or MIGRATED (a valid snapshot, the newest of schema
 * `version`): values[] then holds that page's values of the keys it has
 * (the others keep their defaults). False (defaults in force): values[]
 * untouched. n <= 4. */
bool km_store_peek(const km_flash_t *f, uint16_t version, const uint8_t *keys, uint32_t n, uint32_t *values);

#endif
