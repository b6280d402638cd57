/* SPDX-License-Identifier: Apache-2.0 */
/* The update state machine (km_update.h, docs/update.md). */
#include "km_update.h"

#include <string.h>

#include "km_boot_check.h"
#include "km_crc32.h"

#define PRV_CHUNK 64u

/* Records r as the last result. */
static km_update_result_t prv_result(km_update_t *u, km_update_result_t r)
{
    u->result = (uint8_t)r;
    return r;
}

/* Records r and fails the session. */
static km_update_result_t prv_fail(km_update_t *u, km_update_result_t r)
{
    u->state = KM_UPD_STATE_FAILED;
    return prv_result(u, r);
}

void km_update_init(km_update_t *u, const km_flash_t *region, const km_image_target_t *target)
{
    memset(u, 0, sizeof *u);
    u->flash = region;
    u->target = *target;
    u->state = KM_UPD_STATE_IDLE;
}

void km_update_reset(km_update_t *u)
{
    u->state = KM_UPD_STATE_IDLE;
    u->blocks = 0u;
    u->received = 0u;
    u->result = KM_UPD_OK;
}

bool km_update_has(const km_update_t *u, uint32_t block)
{
    return block < u->blocks && (u->bitmap[block / 8u] & (1u << (block % 8u))) != 0u;
}

/* Erase one page and read it back all 0xFF. */
static bool prv_erase_page(const km_flash_t *f, uint32_t page)
{
    if (f->erase(f->ctx, page) != KM_FLASH_OK) {
        return false;
    }
    uint8_t buf[PRV_CHUNK];
    for (uint32_t off = 0; off < f->page_size; off += PRV_CHUNK) {
        if (f->read(f->ctx, page * f->page_size + off, buf, PRV_CHUNK) != KM_FLASH_OK) {
            return false;
        }
        for (uint32_t i = 0; i < PRV_CHUNK; i++) {
            if (buf[i] != 0xFFu) {
                return false;
            }
        }
    }
    return true;
}

km_update_result_t km_update_begin(km_update_t *u, const uint8_t header[KM_IMAGE_HEADER_SIZE])
{
    km_image_header_t h;
    switch (km_image_check(header, &u->target, &h)) {
    case KM_IMAGE_OK:
        break;
    case KM_IMAGE_WRONG_MODEL:
        return prv_result(u, KM_UPD_WRONG_MODEL);
    case KM_IMAGE_BAD_SIZE:
        return prv_result(u, KM_UPD_TOO_BIG);
    default:
        return prv_result(u, KM_UPD_BAD_HEADER);
    }
    const km_flash_t *f = u->flash;
    const uint32_t blocks = (h.length + KM_UPDATE_BLOCK - 1u) / KM_UPDATE_BLOCK;
    if (blocks > KM_UPDATE_MAX_BLOCKS || f->prog_size > KM_UPDATE_MAX_CELL ||
        blocks * KM_UPDATE_BLOCK > f->page_size * f->page_count) {
        return prv_result(u, KM_UPD_TOO_BIG);
    }
    /* From here the old image is given up: the session's state is set
     * first, so a failed erase leaves FAILED, not a stale session. */
    memcpy(u->header, header, KM_IMAGE_HEADER_SIZE);
    u->hdr = h;
    u->blocks = (uint16_t)blocks;
    u->received = 0u;
    memset(u->bitmap, 0, sizeof u->bitmap);
    u->state = KM_UPD_STATE_FAILED;
    /* Page 0 first: the header goes before any other page, so a cut
     * anywhere from here leaves no image that looks whole. */
    const uint32_t pages = (blocks * KM_UPDATE_BLOCK + f->page_size - 1u) / f->page_size;
    for (uint32_t p = 0; p < pages; p++) {
        if (!prv_erase_page(f, p)) {
            return prv_fail(u, KM_UPD_FLASH);
        }
    }
    u->state = KM_UPD_STATE_RECEIVING;
    return prv_result(u, KM_UPD_OK);
}

/* Flash bytes [off, off + n) equal data? false on a read error too. */
static bool prv_same(const km_flash_t *f, uint32_t off, const uint8_t *data, uint32_t n)
{
    uint8_t buf[PRV_CHUNK];
    for (uint32_t i = 0; i < n; i += PRV_CHUNK) {
        uint32_t k = n - i < PRV_CHUNK ? n - i : PRV_CHUNK;
        if (f->read(f->ctx, off + i, buf, k) != KM_FLASH_OK || memcmp(buf, data + i, k) != 0) {
            return false;
        }
    }
    return true;
}

km_update_result_t km_update_write(km_update_t *u, uint32_t block, const uint8_t data[KM_UPDATE_BLOCK],
                                   uint32_t crc)
{
    if (u->state != KM_UPD_STATE_RECEIVING) {
        return prv_result(u, KM_UPD_BAD_STATE);
    }
    if (block >= u->blocks) {
        return prv_result(u, KM_UPD_BAD_BLOCK);
    }
    if (km_crc32(0u, data, KM_UPDATE_BLOCK) != crc) {
        return prv_result(u, KM_UPD_BAD_CRC);
    }
    if (block == 0u && memcmp(data, u->header, KM_IMAGE_HEADER_SIZE) != 0) {
        return prv_result(u, KM_UPD_MISMATCH);
    }
    const km_flash_t *f = u->flash;
    const uint32_t cell = f->prog_size;
    /* The commit cell (block 0's first cell) is never programmed here. */
    const uint32_t skip = block == 0u ? cell : 0u;
    const uint32_t base = block * KM_UPDATE_BLOCK;
    if (km_update_has(u, block)) {
        /* A re-send: every cell was programmed once already; compare only. */
        return prv_result(u, prv_same(f, base + skip, data + skip, KM_UPDATE_BLOCK - skip) ? KM_UPD_OK
                                                                                           : KM_UPD_MISMATCH);
    }
    /* One cell per call: a cut tears at most that cell. */
    for (uint32_t i = skip; i < KM_UPDATE_BLOCK; i += cell) {
        if (f->program(f->ctx, base + i, data + i, cell) != KM_FLASH_OK) {
            return prv_fail(u, KM_UPD_FLASH);
        }
    }
    if (!prv_same(f, base + skip, data + skip, KM_UPDATE_BLOCK - skip)) {
        return prv_fail(u, KM_UPD_FLASH);
    }
    u->bitmap[block / 8u] = (uint8_t)(u->bitmap[block / 8u] | (1u << (block % 8u)));
    u->received++;
    return prv_result(u, KM_UPD_OK);
}

km_update_result_t km_update_verify(km_update_t *u, uint32_t *crc)
{
    *crc = 0u;
    if (u->state != KM_UPD_STATE_RECEIVING && u->state != KM_UPD_STATE_VERIFIED) {
        return prv_result(u, KM_UPD_BAD_STATE);
    }
    if (u->received != u->blocks) {
        return prv_result(u, KM_UPD_MISSING);
    }
    const km_flash_t *f = u->flash;
    const uint32_t cell = f->prog_size;
    /* The commit cell from RAM (it is not in flash yet), the rest read back. */
    uint32_t all = km_crc32(0u, u->header, cell);
    uint8_t head[KM_IMAGE_HEADER_SIZE];
    memcpy(head, u->header, cell);
    if (f->read(f->ctx, cell, head + cell, KM_IMAGE_HEADER_SIZE - cell) != KM_FLASH_OK) {
        return prv_fail(u, KM_UPD_FLASH);
    }
    all = km_crc32(all, head + cell, KM_IMAGE_HEADER_SIZE - cell);
    uint32_t body = 0u;
    if (!km_boot_crc(f, KM_IMAGE_HEADER_SIZE, u->hdr.length, &body)) {
        return prv_fail(u, KM_UPD_FLASH);
    }
    if (!km_boot_crc(f, KM_IMAGE_HEADER_SIZE, u->hdr.length, &all)) {
        return prv_fail(u, KM_UPD_FLASH);
    }
    *crc = all;
    if (memcmp(head, u->header, KM_IMAGE_HEADER_SIZE) != 0 || body != u->hdr.body_crc) {
        return prv_fail(u, KM_UPD_VERIFY_FAIL);
    }
    u->state = KM_UPD_STATE_VERIFIED;
    return prv_result(u, KM_UPD_OK);
}

km_update_result_t km_update_commit(km_update_t *u)
{
    if (u->state != KM_UPD_STATE_VERIFIED) {
        return prv_result(u, KM_UPD_BAD_STATE);
    }
    const km_flash_t *f = u->flash;
    km_image_header_t h; /* a header for km_boot_check to fill: its only callers pass one */
    if (f->program(f->ctx, 0u, u->header, f->prog_size) != KM_FLASH_OK ||
        !prv_same(f, 0u, u->header, f->prog_size) || !km_boot_check(f, &u->target, &h)) {
        return prv_fail(u, KM_UPD_FLASH);
    }
    u->state = KM_UPD_STATE_COMMITTED;
    return prv_result(u, KM_UPD_OK);
}
