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
