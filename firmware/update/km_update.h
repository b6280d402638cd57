/* SPDX-License-Identifier: Apache-2.0 */
/* The update state machine (docs/update.md §4): an image in 128-byte blocks
 * into the application region (page 0 of its km_flash_t), made bootable by
 * one last program, the commit cell. Pure. Keeps §7's flash rules: nothing
 * erased before the header passed; page 0 erased first; each cell
 * programmed once, in a page erased and blank-checked this session; the
 * commit cell last, after VERIFY. */
#ifndef KM_UPDATE_H
#define KM_UPDATE_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"
#include "km_image.h"

#define KM_UPDATE_BLOCK 128u
#define KM_UPDATE_MAX_BLOCKS 1024u /* 128 KiB: the largest region is 112 KiB */
#define KM_UPDATE_MAX_CELL 8u

typedef enum {
    KM_UPD_STATE_APP = 0,   /* the application's STATUS answer */
    KM_UPD_STATE_IDLE,      /* bootloader, no session */
    KM_UPD_STATE_RECEIVING, /* erased, taking blocks */
    KM_UPD_STATE_VERIFIED,  /* every block in, CRCs matched */
    KM_UPD_STATE_COMMITTED, /* commit cell programmed, boot check passed */
    KM_UPD_STATE_FAILED,    /* a flash error: BEGIN starts over */
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
    KM_UPD_MISMATCH = 9,     /* block 0 vs header, or a re-sent block differs */
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

/* ENTER: ends any session (IDLE), flash untouched. */
void km_update_reset(km_update_t *u);

/* BEGIN: checks the header, then erases the pages the image needs. */
km_update_result_t km_update_begin(km_update_t *u, const uint8_t header[KM_IMAGE_HEADER_SIZE]);
/* WRITE: programs and reads back one block; a re-send only compares. */
km_update_result_t km_update_write(km_update_t *u, uint32_t block, const uint8_t data[KM_UPDATE_BLOCK],
                                   uint32_t crc);
/* VERIFY. *crc: CRC-32 of image bytes [0, length) as read back (0 if not computed). */
km_update_result_t km_update_verify(km_update_t *u, uint32_t *crc);
/* COMMIT: programs the commit cell, then runs the boot check. */
km_update_result_t km_update_commit(km_update_t *u);

/* Whether `block` was received. */
bool km_update_has(const km_update_t *u, uint32_t block);

#endif
