/* SPDX-License-Identifier: Apache-2.0 */
/* Template: the user-data store's flash region (km_hal_flash.h). Offsets are
 * from the region start; keep NOR rules: erase to 0xFF, program whole
 * aligned cells onto erased cells only, report torn cells as ECC errors. */
#include <stddef.h>

#include "km_board.h"

/* Unlock, erase one page, wait, lock; blank-check the page. */
static km_flash_result_t prv_erase(void *ctx, uint32_t page)
{
    (void)ctx;
    (void)page;
    return KM_FLASH_ERR_ERASE;
}

/* Check alignment and bounds (ERR_ALIGN), check the cells are erased
 * (ERR_PROGRAM, nothing written), program cell by cell, verify. */
static km_flash_result_t prv_program(void *ctx, uint32_t offset, const void *data, uint32_t len)
{
    (void)ctx;
    (void)offset;
    (void)data;
    (void)len;
    return KM_FLASH_ERR_PROGRAM;
}

/* Copy out of the memory-mapped region; map an ECC fault to ERR_ECC. */
static km_flash_result_t prv_read(void *ctx, uint32_t offset, void *data, uint32_t len)
{
    (void)ctx;
    (void)offset;
    (void)data;
    (void)len;
    return KM_FLASH_ERR_ECC;
}

/* Geometry comes from the linker script's store-region symbols. */
const km_flash_t *km_board_flash(void)
{
    static const km_flash_t s_flash = {
        .page_size = 0u,
        .prog_size = 4u,
        .page_count = 0u,
        .erase = prv_erase,
        .program = prv_program,
        .read = prv_read,
        .ctx = NULL,
    };
    return &s_flash;
}
