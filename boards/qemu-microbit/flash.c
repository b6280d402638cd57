/* SPDX-License-Identifier: Apache-2.0 */
/* The user-data store region (km_hal_flash.h) on the nRF51 NVMC.
 *
 * The region is the top flash pages the linker script reserves; offsets are
 * from its start. Cells are 4 bytes (the NVMC programs whole words). The
 * driver enforces the NOR rules the store relies on rather than trusting the
 * caller: program only onto erased cells (a cell already holding 0xFFFFFFFF
 * cannot be told apart, which is harmless), blank-check after erase, verify
 * after program. In QEMU a page outside the loaded image reads 0x00 until it
 * is first erased; a real part ships it erased (0xFF). */
#include <stdbool.h>
#include <string.h>

#include "km_board.h"
#include "km_hal_flash.h"
#include "nrf51_regs.h"

#define PRV_PAGE_SIZE 1024u
#define PRV_CELL 4u
#define PRV_ERASED 0xFFFFFFFFu

extern const uint8_t __km_store_start[];
extern const uint8_t __km_store_size[];

static uint32_t prv_base(void)
{
    return (uint32_t)(uintptr_t)__km_store_start;
}

static uint32_t prv_size(void)
{
    return (uint32_t)(uintptr_t)__km_store_size;
}

static volatile uint32_t *prv_word(uint32_t offset)
{
    return (volatile uint32_t *)(uintptr_t)(prv_base() + offset);
}

static void prv_wait_ready(void)
{
    /* The CPU stalls on flash fetches during a write anyway; READY guards
     * against starting the next operation too early (RM §6.1). */
    while (NRF_REG(NRF_NVMC, NVMC_READY) == 0u) {
    }
}

static void prv_config(uint32_t mode)
{
    NRF_REG(NRF_NVMC, NVMC_CONFIG) = mode;
    prv_wait_ready();
}

static bool prv_in_region(uint32_t offset, uint32_t len)
{
    return offset <= prv_size() && len <= prv_size() - offset;
}

static km_flash_result_t prv_erase(void *ctx, uint32_t page)
{
    (void)ctx;
    if (page >= prv_size() / PRV_PAGE_SIZE) {
        return KM_FLASH_ERR_ALIGN;
    }
    uint32_t offset = page * PRV_PAGE_SIZE;
    prv_config(NVMC_CONFIG_EEN);
    NRF_REG(NRF_NVMC, NVMC_ERASEPAGE) = prv_base() + offset;
    prv_wait_ready();
    prv_config(NVMC_CONFIG_REN);
    for (uint32_t i = 0; i < PRV_PAGE_SIZE; i += PRV_CELL) {
        if (*prv_word(offset + i) != PRV_ERASED) {
            return KM_FLASH_ERR_ERASE;
        }
    }
    return KM_FLASH_OK;
}

static km_flash_result_t prv_program(void *ctx, uint32_t offset, const void *data, uint32_t len)
{
    (void)ctx;
    if (offset % PRV_CELL != 0u || len % PRV_CELL != 0u || !prv_in_region(offset, len)) {
        return KM_FLASH_ERR_ALIGN;
    }
    /* Check first, write second: a refused program leaves flash untouched. */
    for (uint32_t i = 0; i < len; i += PRV_CELL) {
        if (*prv_word(offset + i) != PRV_ERASED) {
            return KM_FLASH_ERR_PROGRAM;
        }
    }
    const uint8_t *src = data;
    prv_config(NVMC_CONFIG_WEN);
    for (uint32_t i = 0; i < len; i += PRV_CELL) {
        uint32_t word;
        memcpy(&word, src + i, sizeof word); /* caller's buffer may be unaligned */
        *prv_word(offset + i) = word;
        prv_wait_ready();
    }
    prv_config(NVMC_CONFIG_REN);
    for (uint32_t i = 0; i < len; i += PRV_CELL) {
        uint32_t word;
        memcpy(&word, src + i, sizeof word);
        if (*prv_word(offset + i) != word) {
            return KM_FLASH_ERR_PROGRAM;
        }
    }
    return KM_FLASH_OK;
}

static km_flash_result_t prv_read(void *ctx, uint32_t offset, void *data, uint32_t len)
{
    (void)ctx;
    if (!prv_in_region(offset, len)) {
        return KM_FLASH_ERR_ALIGN;
    }
    /* Flash is memory mapped; the nRF51 has no flash ECC to report. */
    memcpy(data, (const void *)(uintptr_t)(prv_base() + offset), len);
    return KM_FLASH_OK;
}

const km_flash_t *km_board_flash(void)
{
    static km_flash_t s_flash;
    s_flash.page_size = PRV_PAGE_SIZE;
    s_flash.prog_size = PRV_CELL;
    s_flash.page_count = prv_size() / PRV_PAGE_SIZE;
    s_flash.erase = prv_erase;
    s_flash.program = prv_program;
    s_flash.read = prv_read;
    s_flash.ctx = NULL;
    return &s_flash;
}
