/* SPDX-License-Identifier: Apache-2.0 */
/* Update mode's ID and baud (km_boot_address.h, docs/update.md §3). */
#include "km_boot_address.h"

#include "km_frame.h"
#include "km_store_peek.h"

void km_boot_address(const volatile km_boot_shared_t *sh, bool asked, const km_flash_t *store,
                     uint16_t schema, km_boot_address_t *out)
{
    static const uint8_t k_keys[2] = {0x0Fu, 0x10u};
    if (asked && km_boot_handoff_get(sh, &out->id, &out->baud)) {
        return;
    }
    out->id = (uint8_t)(store != 0 ? KM_BOOT_FALLBACK_ID : KM_BOOT_NO_READER_ID);
    out->baud = KM_BOOT_FALLBACK_BAUD;
    uint32_t v[2] = {0u, KM_BOOT_FALLBACK_BAUD / 100u};
    if (store != 0 && km_store_peek(store, schema, k_keys, 2u, v)) {
        out->id = v[0] <= KM_ID_MAX ? (uint8_t)v[0] : KM_BOOT_FALLBACK_ID;
        out->baud = v[1] * 100u;
    }
}
