/* SPDX-License-Identifier: Apache-2.0 */
/* Image header decode and check (docs/update.md §2). */
#include "km_image.h"

#include <stddef.h>
#include <string.h>

#include "km_crc32.h"

_Static_assert(sizeof(km_image_header_t) == 8u * sizeof(uint32_t) &&
                   offsetof(km_image_header_t, head_crc) == 7u * sizeof(uint32_t),
               "km_image_header_t is the eight header words, in order, unpadded");

/* The header's fields from its (little-endian) bytes. */
void km_image_decode(const uint8_t raw[KM_IMAGE_HEADER_SIZE], km_image_header_t *h)
{
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    memcpy(h, raw, sizeof *h);
#else
    uint32_t w[8];
    const uint8_t *p = raw;
    for (uint32_t i = 0; i < 8u; i++, p += 4) {
        w[i] = (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
    }
    memcpy(h, w, sizeof w);
#endif
}

km_image_verdict_t km_image_check(const uint8_t raw[KM_IMAGE_HEADER_SIZE], const km_image_target_t *t,
                                  km_image_header_t *h)
{
    km_image_header_t local = {0};
    km_image_header_t *d = h != 0 ? h : &local;
    km_image_decode(raw, d);
    if (d->magic != KM_IMAGE_MAGIC || km_crc32(0u, raw, 28u) != d->head_crc) {
        return KM_IMAGE_BAD_HEADER;
    }
    if (d->model != t->model) {
        return KM_IMAGE_WRONG_MODEL;
    }
    if (d->vectors != KM_IMAGE_VECTORS || d->base != t->base) {
        return KM_IMAGE_BAD_HEADER;
    }
    if (d->length < KM_IMAGE_MIN_LEN || d->length > t->region_size) {
        return KM_IMAGE_BAD_SIZE;
    }
    return KM_IMAGE_OK;
}
