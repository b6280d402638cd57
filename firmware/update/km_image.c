/* SPDX-License-Identifier: Apache-2.0 */
/* Image header decode and check (docs/update.md §2). */
#include "km_image.h"

#include "km_crc32.h"

static uint32_t prv_le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

void km_image_decode(const uint8_t raw[KM_IMAGE_HEADER_SIZE], km_image_header_t *h)
{
    h->magic = prv_le32(raw + 0);
    h->model = prv_le32(raw + 4);
    h->length = prv_le32(raw + 8);
    h->version = prv_le32(raw + 12);
    h->vectors = prv_le32(raw + 16);
    h->base = prv_le32(raw + 20);
    h->body_crc = prv_le32(raw + 24);
    h->head_crc = prv_le32(raw + 28);
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
