/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: the flash region of the user-data store, pages 0..page_count-1, NOR rules
 * (docs/architecture.md "HAL contracts"). */
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
