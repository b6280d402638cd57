/* SPDX-License-Identifier: Apache-2.0 */
/* The boot decision (docs/update.md §3). */
#include "km_boot_check.h"

#include "km_crc32.h"

#define PRV_CHUNK 64u

bool km_boot_crc(const km_flash_t *region, uint32_t from, uint32_t to, uint32_t *crc)
{
    uint8_t buf[PRV_CHUNK];
    while (from < to) {
        uint32_t n = to - from < PRV_CHUNK ? to - from : PRV_CHUNK;
        if (region->read(region->ctx, from, buf, n) != KM_FLASH_OK) {
            return false;
        }
        *crc = km_crc32(*crc, buf, n);
        from += n;
    }
    return true;
}

bool km_boot_check(const km_flash_t *region, const km_image_target_t *t, km_image_header_t *h)
{
    uint8_t raw[KM_IMAGE_HEADER_SIZE];
    km_image_header_t local = {0};
    km_image_header_t *d = h != 0 ? h : &local;
    if (region->read(region->ctx, 0u, raw, sizeof raw) != KM_FLASH_OK) {
        d->magic = 0u;
        return false;
    }
    if (km_image_check(raw, t, d) != KM_IMAGE_OK) {
        return false;
    }
    uint32_t crc = 0u;
    return km_boot_crc(region, KM_IMAGE_HEADER_SIZE, d->length, &crc) && crc == d->body_crc;
}

/* The little-endian word at b. */
static uint32_t prv_le32(const uint8_t *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}

bool km_boot_entry(const km_flash_t *region, const km_image_header_t *h, uint32_t sp_lo, uint32_t sp_hi,
                   km_boot_entry_t *e)
{
    uint8_t table[8] = {0};
    const bool read = region->read(region->ctx, h->vectors, table, sizeof table) == KM_FLASH_OK;
    e->sp = prv_le32(table);
    e->pc = prv_le32(table + 4);
    const uint32_t code = e->pc & ~1u; /* the first instruction's address */
    const uint32_t from = h->base + h->vectors;
    const uint32_t end = h->base + h->length; /* km_boot_check: length <= region size */
    return read && e->sp >= sp_lo && e->sp <= sp_hi && (e->pc & 1u) != 0u && code >= from && code < end &&
           end - code >= 2u;
}
