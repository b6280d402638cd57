/* SPDX-License-Identifier: Apache-2.0 */
/* Where update mode answers (docs/update.md §3): the ID and baud the
 * application handed over, else the stored pair or a fallback. Pure. */
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

/* Fills *out. asked: the decision was KM_BOOT_STAY_ASKED; store: the
 * user-data store of `schema`, NULL without the store reader. */
void km_boot_address(const volatile km_boot_shared_t *sh, bool asked, const km_flash_t *store,
                     uint16_t schema, km_boot_address_t *out);

#endif
