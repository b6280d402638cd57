/* SPDX-License-Identifier: Apache-2.0 */
/* Where the bootloader's update mode answers (docs/update.md §3): at the ID
 * and baud the application handed over with its ENTER request; else, with
 * the store reader, at the stored ones (km_store_peek: what a mount of
 * 0x0F and 0x10 would load) or ID 0 at 115200; without it (the 32 KiB
 * STM32G031F6, whose bootloader has no room for it), at ID 1, 115200.
 * Pure: the shared words and the store are passed in. */
#ifndef KM_BOOT_ADDRESS_H
#define KM_BOOT_ADDRESS_H

#include <stdbool.h>
#include <stdint.h>

#include "km_boot_trial.h"
#include "km_hal_flash.h"

#define KM_BOOT_FALLBACK_BAUD 115200u
#define KM_BOOT_FALLBACK_ID 0u  /* store reader, nothing stored */
#define KM_BOOT_NO_READER_ID 1u /* no store reader */

typedef struct {
    uint8_t id;
    uint32_t baud;
} km_boot_address_t;

/* asked: the trial decision was KM_BOOT_STAY_ASKED; store: the user-data
 * store of `schema`, or NULL for a bootloader without the store reader. */
void km_boot_address(const volatile km_boot_shared_t *sh, bool asked, const km_flash_t *store,
                     uint16_t schema, km_boot_address_t *out);

#endif
