/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: the flash region that holds the user-data store.
 *
 * The store sees its region as pages numbered 0..page_count-1 and byte
 * offsets from the region's start. A board (or the NOR simulator in tests)
 * fills one km_flash_t. Rules every implementation keeps, as NOR flash does:
 *  - erase sets a whole page to 0xFF;
 *  - program writes whole cells (`prog_size` bytes, aligned) and only onto
 *    erased cells: programming a cell twice between erases is an error
 *    (a program cut by power loss before any bit moved leaves the cell
 *    reading erased, and the controller's erased check accepts it again);
 *  - read may report an ECC error for a cell whose program was torn. */
#ifndef KM_HAL_FLASH_H
#define KM_HAL_FLASH_H

#include <stdint.h>

typedef enum {
    KM_FLASH_OK = 0,
    KM_FLASH_ERR_ALIGN,   /* offset/length not a whole number of cells, or out of region */
    KM_FLASH_ERR_PROGRAM, /* cell not erased, or the controller reported a program error */
    KM_FLASH_ERR_ERASE,   /* erase failed */
    KM_FLASH_ERR_ECC,     /* read hit an uncorrectable ECC error (data not trustworthy) */
} km_flash_result_t;

typedef struct km_flash {
    uint32_t page_size;  /* erase unit in bytes */
    uint32_t prog_size;  /* program unit (cell) in bytes: 2, 4 or 8 */
    uint32_t page_count; /* pages in the store's region */
    km_flash_result_t (*erase)(void *ctx, uint32_t page);
    km_flash_result_t (*program)(void *ctx, uint32_t offset, const void *data, uint32_t len);
    km_flash_result_t (*read)(void *ctx, uint32_t offset, void *data, uint32_t len);
    void *ctx;
} km_flash_t;

#endif
