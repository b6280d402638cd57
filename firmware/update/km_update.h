/* SPDX-License-Identifier: Apache-2.0 */
/* The update state machine (docs/update.md §4, §7): a session that takes an
 * image in 128-byte blocks into the application region and makes it
 * bootable with a single program at the end (the commit cell).
 *
 * Pure C over a km_flash_t whose page 0 is the application region's first
 * page: it cannot address the bootloader or the user-data store. No heap,
 * no hardware. Rules it keeps (the power-cut runner checks them):
 *  - nothing is erased before the header passed every check (model first);
 *  - page 0 (the header) is erased first, every page it programs it erased
 *    and blank-checked in this session, and it programs each cell once;
 *  - the first program cell of the image is programmed last, by COMMIT,
 *    after the whole image was read back and its CRC-32s matched. */
#ifndef KM_UPDATE_H
#define KM_UPDATE_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"
#include "km_image.h"

#define KM_UPDATE_BLOCK 128u
#define KM_UPDATE_MAX_BLOCKS 1024u /* 128 KiB of image: the largest region is 112 KiB */
#define KM_UPDATE_MAX_CELL 8u

typedef enum {
    KM_UPD_STATE_APP = 0,   /* the application is running (its STATUS answer) */
    KM_UPD_STATE_IDLE,      /* bootloader, no session */
    KM_UPD_STATE_RECEIVING, /* erased, taking blocks */
    KM_UPD_STATE_VERIFIED,  /* every block in, CRCs matched */
    KM_UPD_STATE_COMMITTED, /* commit cell programmed, boot check passed */
    KM_UPD_STATE_FAILED,    /* a flash error: a new BEGIN starts over */
} km_update_state_t;

typedef enum {
    KM_UPD_OK = 0,
    KM_UPD_BAD_LENGTH = 1, /* params of the wrong size */
    KM_UPD_BAD_STATE = 2,  /* not allowed in this state */
    KM_UPD_BAD_MAGIC = 3,  /* ENTER/START magic */
    KM_UPD_BAD_HEADER = 4,
    KM_UPD_WRONG_MODEL = 5,
    KM_UPD_TOO_BIG = 6,      /* image length out of range */
    KM_UPD_BAD_BLOCK = 7,    /* block index beyond the image */
    KM_UPD_BAD_CRC = 8,      /* block CRC-32 */
    KM_UPD_MISMATCH = 9,     /* block 0 vs the header, or a re-sent block that differs */
    KM_UPD_FLASH = 10,       /* erase, program or read-back failed */
    KM_UPD_VERIFY_FAIL = 11, /* read-back CRC differs */
    KM_UPD_MISSING = 12,     /* VERIFY with blocks missing */
} km_update_result_t;

typedef struct {
    const km_flash_t *flash;
    km_image_target_t target;
    uint8_t state;   /* km_update_state_t */
    uint8_t result;  /* km_update_result_t of the last operation */
    uint16_t blocks; /* of the session's image */
    uint16_t received;
    uint8_t header[KM_IMAGE_HEADER_SIZE]; /* BEGIN's; its first cell is the commit cell */
    km_image_header_t hdr;
    uint8_t bitmap[KM_UPDATE_MAX_BLOCKS / 8u];
} km_update_t;

/* target.region_size must equal the flash's page_size * page_count. */
void km_update_init(km_update_t *u, const km_flash_t *region, const km_image_target_t *target);

/* ENTER in the bootloader: ends any session (state IDLE), flash untouched. */
void km_update_reset(km_update_t *u);

km_update_result_t km_update_begin(km_update_t *u, const uint8_t header[KM_IMAGE_HEADER_SIZE]);
km_update_result_t km_update_write(km_update_t *u, uint32_t block, const uint8_t data[KM_UPDATE_BLOCK],
                                   uint32_t crc);
/* *crc: CRC-32 of image bytes [0, length) as read back (0 if not computed). */
km_update_result_t km_update_verify(km_update_t *u, uint32_t *crc);
km_update_result_t km_update_commit(km_update_t *u);

bool km_update_has(const km_update_t *u, uint32_t block);

#endif
