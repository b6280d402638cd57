/* SPDX-License-Identifier: Apache-2.0 */
/* The application image's header (docs/update.md §2), checked by BEGIN and
 * at every reset. Pure. */
#ifndef KM_IMAGE_H
#define KM_IMAGE_H

#include <stdint.h>

#define KM_IMAGE_MAGIC 0x57464D4Bu /* bytes 4B 4D 46 57, "KMFW" */
#define KM_IMAGE_HEADER_SIZE 32u
/* The vector table's offset in the image: 0x100 (256-aligned, so the
 * bootloader can point VTOR at it) unless the build sets it; the
 * STM32G031F6's 32 KiB build sets 0x20, right after the header, and its
 * bootloader leaves VTOR alone (docs/update.md §2). */
#ifndef KM_IMAGE_VECTORS
#define KM_IMAGE_VECTORS 0x100u
#endif
#define KM_IMAGE_MIN_LEN (KM_IMAGE_VECTORS + 8u) /* at least initial SP + reset vector */

/* Board models (docs/update.md §2). */
#define KM_MODEL_QEMU_MICROBIT 0x4B4D0001u
#define KM_MODEL_STM32G031 0x4B4D0002u

typedef struct {
    uint32_t magic;
    uint32_t model;
    uint32_t length;   /* bytes of the image, header included */
    uint32_t version;  /* the application's 0x0C value, bootloader byte 0 */
    uint32_t vectors;  /* vector table offset from the image start */
    uint32_t base;     /* address the image is linked for */
    uint32_t body_crc; /* CRC-32 of bytes [32, length) */
    uint32_t head_crc; /* CRC-32 of bytes [0, 28) */
} km_image_header_t;

typedef enum {
    KM_IMAGE_OK = 0,
    KM_IMAGE_BAD_HEADER,  /* magic, header CRC, vectors or base */
    KM_IMAGE_WRONG_MODEL, /* an image for another board */
    KM_IMAGE_BAD_SIZE,    /* length below the minimum or above the region */
} km_image_verdict_t;

/* What a board accepts. */
typedef struct {
    uint32_t model;
    uint32_t base;        /* the application region's address */
    uint32_t region_size; /* bytes of the application region */
} km_image_target_t;

void km_image_decode(const uint8_t raw[KM_IMAGE_HEADER_SIZE], km_image_header_t *h);

/* Checks a header against the board; fills *h (may be NULL). A wrong model
 * is reported only for an otherwise sound header. */
km_image_verdict_t km_image_check(const uint8_t raw[KM_IMAGE_HEADER_SIZE], const km_image_target_t *t,
                                  km_image_header_t *h);

#endif
