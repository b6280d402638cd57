/* SPDX-License-Identifier: Apache-2.0 */
/* km_flash_t over the store pages of the G031's single flash bank (RM0444
 * §3.3): 2 KiB pages, 64-bit double words with ECC. Start-and-wait runs in
 * RAM (prv_run): docs/flash-busy.md. */
#include "km_board.h"

#include <stdbool.h>
#include <string.h>

#include "g0_core.h"
#include "g0_regs.h"
#include "g0_vectors.h"
#include "km_cortex_m.h"

extern const uint8_t __km_store_start[];
extern const uint8_t __km_store_size[];  /* linker symbol: its address is the size */
extern const uint8_t __km_store_pages[]; /* linker symbol: its address is the page count */

#define PROG_SIZE 8u
/* BSY polling bound, well above a 40 ms erase (DS12992 table "Flash memory
 * characteristics"). */
#define BUSY_SPINS 2000000u

static volatile bool s_ecc_nmi;

/* Store region start (linker script). */
static uint32_t prv_region_base(void)
{
    return (uint32_t)(uintptr_t)__km_store_start;
}

/* Store region size. */
static uint32_t prv_region_size(void)
{
    return (uint32_t)(uintptr_t)__km_store_size;
}

/* Polls BSY1/CFGBSY; always inlined, so it runs in RAM inside prv_run. */
static inline __attribute__((always_inline)) bool prv_wait_idle(void)
{
    for (uint32_t i = 0u; i < BUSY_SPINS; i++) {
        if ((FLASH_SR & (FLASH_SR_BSY1 | FLASH_SR_CFGBSY)) == 0u) {
            return true;
        }
    }
    return false;
}

/* Starts one operation and waits, from RAM. Erase (dst == 0): STRT (§3.3.7);
 * program: the two words back to back, masked (§3.3.8). False: still busy. */
G0_RAMFUNC(prv_run) static bool prv_run(uint32_t cr, volatile uint32_t *dst, uint32_t w0, uint32_t w1)
{
    FLASH_CR = cr;
    if (dst == 0) {
        FLASH_CR = cr | FLASH_CR_STRT;
    } else {
        uint32_t key = km_cortex_irq_lock();
        dst[0] = w0;
        dst[1] = w1;
        km_cortex_irq_restore(key);
    }
    return prv_wait_idle();
}

/* Unlock with the KEYR sequence (§3.3.6); clear stale flags (rc_w1). */
static bool prv_begin(void)
{
    if (!prv_wait_idle()) {
        return false;
    }
    if ((FLASH_CR & FLASH_CR_LOCK) != 0u) {
        FLASH_KEYR = FLASH_KEY1;
        FLASH_KEYR = FLASH_KEY2;
    }
    FLASH_SR = FLASH_SR_ERRORS | FLASH_SR_EOP;
    return (FLASH_CR & FLASH_CR_LOCK) == 0u;
}

/* Checks EOP and the error flags, then locks. */
static bool prv_end(bool idle)
{
    uint32_t sr = FLASH_SR;
    FLASH_SR = FLASH_SR_ERRORS | FLASH_SR_EOP;
    FLASH_CR = FLASH_CR_LOCK;
    return idle && (sr & FLASH_SR_ERRORS) == 0u && (sr & FLASH_SR_EOP) != 0u;
}

/* Erases one store page. */
static km_flash_result_t prv_erase(void *ctx, uint32_t page)
{
    (void)ctx;
    if (page >= prv_region_size() / FLASH_PAGE_SIZE) {
        return KM_FLASH_ERR_ALIGN;
    }
    uint32_t pnb = (prv_region_base() - FLASH_MAIN_BASE) / FLASH_PAGE_SIZE + page;
    if (!prv_begin()) {
        FLASH_CR = FLASH_CR_LOCK;
        return KM_FLASH_ERR_ERASE;
    }
    /* §3.3.7 */
    bool idle =
        prv_run(FLASH_CR_EOPIE | FLASH_CR_PER | ((pnb << FLASH_CR_PNB_SHIFT) & FLASH_CR_PNB_MASK), 0, 0u, 0u);
    return prv_end(idle) ? KM_FLASH_OK : KM_FLASH_ERR_ERASE;
}

/* Whether [offset, offset + len) lies in the store region. */
static bool prv_range_ok(uint32_t offset, uint32_t len)
{
    uint32_t size = prv_region_size();
    return offset <= size && len <= size - offset;
}

/* Programs whole double words onto erased cells, read back. */
static km_flash_result_t prv_program(void *ctx, uint32_t offset, const void *data, uint32_t len)
{
    (void)ctx;
    if ((offset % PROG_SIZE) != 0u || (len % PROG_SIZE) != 0u || !prv_range_ok(offset, len)) {
        return KM_FLASH_ERR_ALIGN;
    }
    const uint8_t *src = data;
    for (uint32_t done = 0u; done < len; done += PROG_SIZE) {
        volatile uint32_t *dst = (volatile uint32_t *)(uintptr_t)(prv_region_base() + offset + done);
        uint32_t word[2];
        memcpy(word, src + done, sizeof word);
        /* Erased and ECC-clean only (README.md "Drivers", Flash). */
        FLASH_ECCR = FLASH_ECCR_ECCC | FLASH_ECCR_ECCD;
        s_ecc_nmi = false;
        const bool ones = dst[0] == 0xFFFFFFFFu && dst[1] == 0xFFFFFFFFu;
        if (!ones || s_ecc_nmi || (FLASH_ECCR & FLASH_ECCR_ECCD) != 0u) {
            FLASH_ECCR = FLASH_ECCR_ECCC | FLASH_ECCR_ECCD;
            return KM_FLASH_ERR_PROGRAM;
        }
        if (!prv_begin()) {
            FLASH_CR = FLASH_CR_LOCK;
            return KM_FLASH_ERR_PROGRAM;
        }
        bool idle = prv_run(FLASH_CR_EOPIE | FLASH_CR_PG, dst, word[0], word[1]);
        if (!prv_end(idle) || dst[0] != word[0] || dst[1] != word[1]) {
            return KM_FLASH_ERR_PROGRAM;
        }
    }
    return KM_FLASH_OK;
}

/* Records and clears a double ECC error (§3.3.10); other NMIs park. */
void NMI_Handler(void)
{
    if ((FLASH_ECCR & FLASH_ECCR_ECCD) != 0u) {
        FLASH_ECCR = FLASH_ECCR_ECCD; /* rc_w1 */
        s_ecc_nmi = true;
        return;
    }
    for (;;) { /* the watchdog resets */
    }
}

/* Reads store bytes; KM_FLASH_ERR_ECC on a double ECC error. */
static km_flash_result_t prv_read(void *ctx, uint32_t offset, void *data, uint32_t len)
{
    (void)ctx;
    if (!prv_range_ok(offset, len)) {
        return KM_FLASH_ERR_ALIGN;
    }
    FLASH_ECCR = FLASH_ECCR_ECCC | FLASH_ECCR_ECCD;
    s_ecc_nmi = false;
    const volatile uint8_t *src = (const volatile uint8_t *)(uintptr_t)(prv_region_base() + offset);
    uint8_t *dst = data;
    for (uint32_t i = 0u; i < len; i++) {
        dst[i] = src[i];
    }
    bool ecc = s_ecc_nmi || (FLASH_ECCR & FLASH_ECCR_ECCD) != 0u;
    FLASH_ECCR = FLASH_ECCR_ECCC | FLASH_ECCR_ECCD;
    return ecc ? KM_FLASH_ERR_ECC : KM_FLASH_OK;
}

/* The page count is a link-time constant (the linker script's
 * KM_STORE_PAGES), so the table is const, in flash. */
static const km_flash_t s_flash = {
    .page_size = FLASH_PAGE_SIZE,
    .prog_size = PROG_SIZE,
    .page_count = (uint32_t)(uintptr_t)__km_store_pages,
    .erase = prv_erase,
    .program = prv_program,
    .read = prv_read,
    .ctx = 0,
};

/* The store's flash. */
const km_flash_t *km_board_flash(void)
{
    return &s_flash;
}
