/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: a flash region, NOR rules (docs/architecture.md "HAL contracts"). */
#ifndef KM_HAL_FLASH_H
#define KM_HAL_FLASH_H

#include <stdint.h>

typedef enum {
    KM_FLASH_OK = 0,
    KM_FLASH_ERR_ALIGN,   /* not whole aligned cells, or outside the region */
    KM_FLASH_ERR_PROGRAM, /* cell not erased, or a program error */
    KM_FLASH_ERR_ERASE,
    KM_FLASH_ERR_ECC, /* uncorrectable ECC error */
} km_flash_result_t;

typedef struct km_flash {
    uint32_t page_size;  /* erase unit, bytes */
    uint32_t prog_size;  /* program unit (cell), bytes: 2, 4 or 8 */
    uint32_t page_count; /* pages 0..page_count-1 */
    km_flash_result_t (*erase)(void *ctx, uint32_t page);
    km_flash_result_t (*program)(void *ctx, uint32_t offset, const void *data, uint32_t len);
    km_flash_result_t (*read)(void *ctx, uint32_t offset, void *data, uint32_t len);
    void *ctx;
} km_flash_t;

#endif
