/* SPDX-License-Identifier: Apache-2.0 */
/* Test rig for the firmware update (docs/update.md): a NOR simulator split
 * into an application region (the first pages, the only ones the update's
 * km_flash_t reaches) and user-data store pages above it, and images built
 * as tools/gen/make-image builds them (header, vector table at 0x100, body). */
#ifndef KM_UPDATE_RIG_H
#define KM_UPDATE_RIG_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "km_crc32.h"
#include "km_image.h"
#include "km_nor_sim.h"
#include "km_update.h"

#define RIG_BASE 0x08001000u
#define RIG_MAX_IMAGE 6144u
#define KM_BODY_MAX_TEST 250u

typedef struct {
    km_nor_sim_t sim;
    km_flash_t whole;  /* every page of the simulator */
    km_flash_t region; /* the application region: pages [0, region_pages) */
    km_flash_t store;  /* the store: the pages above */
    uint32_t region_pages;
    km_image_target_t target;
} rig_t;

typedef struct {
    uint32_t length;
    uint32_t version;
    uint8_t bytes[RIG_MAX_IMAGE + KM_UPDATE_BLOCK]; /* padded with 0xFF to whole blocks */
} rig_image_t;

/* A window onto the simulator: page p of the window is page first + p.
 * It refuses anything outside itself, as a board's region driver does. */
typedef struct {
    km_flash_t *whole;
    uint32_t first;
    uint32_t pages;
} rig_window_t;

static rig_window_t s_rig_win_region, s_rig_win_store;

static inline bool rig_win_inside(const rig_window_t *w, uint32_t off, uint32_t n)
{
    const uint32_t size = w->pages * w->whole->page_size;
    return off <= size && n <= size - off;
}

static km_flash_result_t rig_win_erase(void *ctx, uint32_t page)
{
    rig_window_t *w = ctx;
    return page < w->pages ? w->whole->erase(w->whole->ctx, w->first + page) : KM_FLASH_ERR_ALIGN;
}

static km_flash_result_t rig_win_program(void *ctx, uint32_t off, const void *d, uint32_t n)
{
    rig_window_t *w = ctx;
    if (!rig_win_inside(w, off, n)) {
        return KM_FLASH_ERR_ALIGN;
    }
    return w->whole->program(w->whole->ctx, w->first * w->whole->page_size + off, d, n);
}

static km_flash_result_t rig_win_read(void *ctx, uint32_t off, void *d, uint32_t n)
{
    rig_window_t *w = ctx;
    if (!rig_win_inside(w, off, n)) {
        return KM_FLASH_ERR_ALIGN;
    }
    return w->whole->read(w->whole->ctx, w->first * w->whole->page_size + off, d, n);
}

static inline void rig_bind(rig_t *r)
{
    km_nor_sim_bind(&r->sim, &r->whole);
    s_rig_win_region.whole = &r->whole;
    s_rig_win_region.first = 0u;
    s_rig_win_store.whole = &r->whole;
    s_rig_win_region.pages = r->region_pages;
    s_rig_win_store.first = r->region_pages;
    s_rig_win_store.pages = r->whole.page_count - r->region_pages;
    r->region = (km_flash_t){.page_size = r->whole.page_size,
                             .prog_size = r->whole.prog_size,
                             .page_count = r->region_pages,
                             .erase = rig_win_erase,
                             .program = rig_win_program,
                             .read = rig_win_read,
                             .ctx = &s_rig_win_region};
    r->store = r->region;
    r->store.page_count = r->whole.page_count - r->region_pages;
    r->store.ctx = &s_rig_win_store;
    r->target.model = KM_MODEL_STM32G031;
    r->target.base = RIG_BASE;
    r->target.region_size = r->region_pages * r->whole.page_size;
}

static inline void rig_put32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) {
        p[i] = (uint8_t)(v >> (8 * i));
    }
}

/* A simulator of `pages` pages, the first region_pages of them the
 * application region, with a real controller's rules. */
static inline void rig_init(rig_t *r, uint32_t page_size, uint32_t cell, uint32_t pages,
                            uint32_t region_pages, uint8_t fill)
{
    const km_nor_sim_config_t cfg = {page_size, cell, pages, fill};
    memset(r, 0, sizeof *r);
    (void)km_nor_sim_init(&r->sim, &cfg, &r->whole);
    const km_nor_sim_rules_t rules = {.ecc_dword = cell == 8u, .content_check = true};
    km_nor_sim_set_rules(&r->sim, &rules);
    r->region_pages = region_pages;
    rig_bind(r);
}

/* An image of `length` bytes whose body is a seeded xorshift stream. */
static inline void rig_make_image(rig_image_t *im, uint32_t length, uint32_t version, uint32_t model,
                                  uint32_t seed)
{
    memset(im->bytes, 0xFF, sizeof im->bytes);
    im->length = length;
    im->version = version;
    uint32_t x = seed | 1u;
    for (uint32_t i = KM_IMAGE_HEADER_SIZE; i < length; i++) {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        im->bytes[i] = (uint8_t)x;
    }
    rig_put32(im->bytes + 0, KM_IMAGE_MAGIC);
    rig_put32(im->bytes + 4, model);
    rig_put32(im->bytes + 8, length);
    rig_put32(im->bytes + 12, version);
    rig_put32(im->bytes + 16, KM_IMAGE_VECTORS);
    rig_put32(im->bytes + 20, RIG_BASE);
    rig_put32(im->bytes + 24, km_crc32(0u, im->bytes + 32, length - 32u));
    rig_put32(im->bytes + 28, km_crc32(0u, im->bytes, 28u));
}

/* Gives im a sound vector table (initial SP, reset vector inside the
 * image) for the entry check (docs/update.md §3) and its CRCs again. */
static inline void rig_set_entry(rig_image_t *im, uint32_t sp, uint32_t pc)
{
    rig_put32(im->bytes + KM_IMAGE_VECTORS, sp);
    rig_put32(im->bytes + KM_IMAGE_VECTORS + 4u, pc);
    rig_put32(im->bytes + 24, km_crc32(0u, im->bytes + 32, im->length - 32u));
    rig_put32(im->bytes + 28, km_crc32(0u, im->bytes, 28u));
}

static inline uint32_t rig_blocks(const rig_image_t *im)
{
    return (im->length + KM_UPDATE_BLOCK - 1u) / KM_UPDATE_BLOCK;
}

/* The WRITE frame body for block b: sub, u16 block, data, u32 CRC. */
static inline uint8_t rig_write_body(const rig_image_t *im, uint32_t b, uint8_t *body)
{
    body[0] = 0x03u;
    body[1] = (uint8_t)b;
    body[2] = (uint8_t)(b >> 8);
    memcpy(body + 3, im->bytes + b * KM_UPDATE_BLOCK, KM_UPDATE_BLOCK);
    rig_put32(body + 3 + KM_UPDATE_BLOCK, km_crc32(0u, body + 3, KM_UPDATE_BLOCK));
    return (uint8_t)(3u + KM_UPDATE_BLOCK + 4u);
}

#endif
