/* SPDX-License-Identifier: Apache-2.0 */
/* Commit, reset and idle compaction of the user-data store (why each step is safe at a power cut:
 * docs/store.md). */
#include <string.h>

#include "km_store.h"
#include "km_store_internal.h"
#include "km_store_record.h"

static uint32_t prv_page_bit(uint32_t page)
{
    return 1u << page;
}

static uint8_t prv_next(const km_store_t *s, uint32_t page)
{
    return (uint8_t)((page + 1u) % s->flash->page_count);
}

/* Erase and blank-check: a page counts as erased only if every cell reads
 * all ones after the erase. */
static bool prv_erase(km_store_t *s, uint32_t page)
{
    const km_flash_t *f = s->flash;
    s->erased &= ~prv_page_bit(page);
    if (f->erase(f->ctx, page) != KM_FLASH_OK) {
        return false;
    }
    if (!km_rec_range_erased(f, page * f->page_size, f->page_size)) {
        return false;
    }
    s->erased |= prv_page_bit(page);
    return true;
}

/* Programs size bytes (whole cells) at addr one cell at a time, then reads them back. */
static bool prv_program_verified(const km_flash_t *f, uint32_t addr, const uint8_t *rec, uint32_t size)
{
    const uint32_t c = f->prog_size;
    uint8_t back[KM_REC_MAX_CELL];
    for (uint32_t at = 0; at < size; at += c) {
        if (f->program(f->ctx, addr + at, &rec[at], c) != KM_FLASH_OK) {
            return false;
        }
    }
    for (uint32_t chk = 0; chk < size; chk += c) {
        if (f->read(f->ctx, addr + chk, back, c) != KM_FLASH_OK || memcmp(back, &rec[chk], c) != 0) {
            return false;
        }
    }
    return true;
}

/* Writes state as a snapshot of the next generation at the start of target (erased), then its confirmation
 * cell K. */
static bool prv_snapshot(km_store_t *s, uint32_t target, const uint32_t *state)
{
    const km_flash_t *f = s->flash;
    s->own = false;
    s->erased &= ~prv_page_bit(target); /* programmed from here on */
    uint8_t buf[KM_REC_MAX_BYTES];
    km_rec_t hdr; /* km_rec_encode reads only the header fields */
    hdr.type = KM_REC_SNAPSHOT;
    hdr.version = s->schema->version;
    hdr.gen = s->gen + 1u;
    hdr.hash = s->hash;
    const uint32_t size =
        km_rec_encode(buf, &hdr, s->schema, state, km_store_all_keys(s->schema), f->prog_size);
    static const uint8_t k_zero[KM_REC_MAX_CELL] = {0};
    const uint32_t at = target * f->page_size;
    const uint32_t body = size - f->prog_size;
    /* The commit cell after the body is read back, K last: a K that reads programmed then proves the snapshot
     * solid. */
    if (!prv_program_verified(f, at, buf, body) ||
        !prv_program_verified(f, at + body, &buf[body], f->prog_size) ||
        !prv_program_verified(f, at + size, k_zero, f->prog_size)) {
        s->target = (uint8_t)target; /* a retry erases it again */
        return false;
    }
    s->suspect &= ~prv_page_bit(target);
    s->active = (uint8_t)target;
    s->gen++;
    s->tail = size + f->prog_size;
    s->own = true;
    return true;
}

/* What prv_compact_step did. */
typedef enum {
    PRV_STEP_ERASED,  /* a page erased: more steps follow */
    PRV_STEP_WRITTEN, /* the snapshot written and confirmed: compaction done */
    PRV_STEP_FAILED,
} prv_step_t;

/* One flash step of a compaction into target: erase the first page without a valid snapshot (target
 * aside), else erase target unless it is erased, else write the snapshot of state there. */
static prv_step_t prv_compact_step(km_store_t *s, uint32_t target, const uint32_t *state)
{
    const km_flash_t *f = s->flash;
    for (uint32_t p = 0; p < f->page_count; p++) {
        if ((s->suspect & prv_page_bit(p)) != 0u && p != target) {
            if (!prv_erase(s, p)) {
                return PRV_STEP_FAILED;
            }
            s->suspect &= ~prv_page_bit(p);
            return PRV_STEP_ERASED;
        }
    }
    if ((s->erased & prv_page_bit(target)) == 0u) {
        return prv_erase(s, target) ? PRV_STEP_ERASED : PRV_STEP_FAILED;
    }
    return prv_snapshot(s, target, state) ? PRV_STEP_WRITTEN : PRV_STEP_FAILED;
}

/* Compacts state into target: prv_compact_step until the snapshot is written or a step fails (inlined: no
 * frame of its own on the deepest stack path, docs/footprint.md "STM32G031F6"). */
static inline __attribute__((always_inline)) bool prv_compact(km_store_t *s, uint32_t target,
                                                              const uint32_t *state)
{
    s->own = false;
    prv_step_t step;
    do {
        step = prv_compact_step(s, target, state);
    } while (step == PRV_STEP_ERASED);
    return step == PRV_STEP_WRITTEN;
}

/* What prv_append_delta did. */
typedef enum {
    PRV_DELTA_WRITTEN,
    PRV_DELTA_NO_ROOM, /* the active page cannot take it: nothing written */
    PRV_DELTA_FAILED,  /* the write failed: nothing may follow it */
} prv_delta_t;

/* Appends the delta record of the `changed` keys of `next` to the active page (noinline: its buffer is off
 * the stack before a compaction runs, docs/footprint.md "STM32G031F6"). */
static __attribute__((noinline)) prv_delta_t prv_append_delta(km_store_t *s, const uint32_t *next,
                                                              uint32_t changed)
{
    const km_flash_t *f = s->flash;
    km_rec_t hdr; /* km_rec_encode reads only the type of a delta */
    hdr.type = KM_REC_DELTA;
    uint8_t buf[KM_REC_MAX_BYTES];
    const uint32_t size = km_rec_encode(buf, &hdr, s->schema, next, changed, f->prog_size);
    if (size > f->page_size - s->tail) {
        return PRV_DELTA_NO_ROOM;
    }
    if (!prv_program_verified(f, s->active * f->page_size + s->tail, buf, size)) {
        return PRV_DELTA_FAILED;
    }
    s->tail += size;
    return PRV_DELTA_WRITTEN;
}

static km_store_status_t prv_commit_state(km_store_t *s, const uint32_t *next)
{
    uint32_t changed = 0;
    for (uint32_t i = 0; i < s->schema->count; i++) {
        if (next[i] != s->values[i]) {
            changed |= 1u << i;
        }
    }
    uint32_t target = s->target;
    const uint32_t *state = next;
    bool failed = false;
    if (s->own) {
        if (changed == 0u) {
            return KM_STORE_OK;
        }
        const prv_delta_t delta = prv_append_delta(s, next, changed);
        if (delta == PRV_DELTA_WRITTEN) {
            memcpy(s->values, next, s->schema->count * sizeof next[0]);
            return KM_STORE_OK;
        }
        target = prv_next(s, s->active);
        if (delta == PRV_DELTA_FAILED) {
            /* The record may be half there and read valid later, or not:
             * nothing may follow it. Put the old state in a fresh page now
             * if the flash lets us. */
            state = s->values;
            failed = true;
        }
    }
    /* Not own: the first commit of the session (or after a failure), which always writes. */
    const bool ok = prv_compact(s, target, state) && !failed;
    if (!ok) {
        return KM_STORE_ERR_FLASH;
    }
    memcpy(s->values, next, s->schema->count * sizeof next[0]);
    return KM_STORE_OK;
}

km_store_status_t km_store_commit(km_store_t *s, const uint8_t *keys, const uint32_t *values, uint32_t n)
{
    if (!s->mounted || n > KM_STORE_MAX_KEYS) {
        return KM_STORE_ERR_ARG;
    }
    uint32_t next[KM_STORE_MAX_KEYS];
    uint32_t seen = 0;
    memcpy(next, s->values, sizeof next);
    for (uint32_t i = 0; i < n; i++) {
        const int32_t at = km_store_index(s->schema, keys[i]);
        if (at < 0 || (seen & (1u << (uint32_t)at)) != 0u) {
            return KM_STORE_ERR_ARG;
        }
        seen |= 1u << (uint32_t)at;
        next[at] = values[i];
    }
    return prv_commit_state(s, next);
}

km_store_status_t km_store_reset(km_store_t *s, const uint8_t *keep, uint32_t n_keep)
{
    if (!s->mounted) {
        return KM_STORE_ERR_ARG;
    }
    uint32_t next[KM_STORE_MAX_KEYS];
    for (uint32_t i = 0; i < s->schema->count; i++) {
        next[i] = s->schema->keys[i].def;
        for (uint32_t k = 0; k < n_keep; k++) {
            if (keep[k] == s->schema->keys[i].key) {
                next[i] = s->values[i];
            }
        }
    }
    return prv_commit_state(s, next);
}

bool km_store_maintain(km_store_t *s)
{
    if (!s->mounted || !s->own) {
        /* Nothing to erase before the session's first commit. */
        return false;
    }
    const km_flash_t *f = s->flash;
    /* Keep room for the largest delta (every key, 4-byte values) so a
     * commit does not wait on an erase. */
    const uint32_t room = km_rec_delta_max_size(s->schema->count, f->prog_size);
    if (f->page_size - s->tail >= room) {
        return false;
    }
    /* The session owns a page, so no page is suspect: the step erases the next page, or compacts into it. */
    (void)prv_compact_step(s, prv_next(s, s->active), s->values);
    return true;
}

/* Idle work before the session's first commit (km_store.h): the steps of
 * that commit's compaction, one flash step per call, writing the state
 * mount loaded. */
bool km_store_prepare(km_store_t *s)
{
    if (!s->mounted || s->own) {
        return false;
    }
    return prv_compact_step(s, s->target, s->values) != PRV_STEP_FAILED;
}

bool km_store_get(const km_store_t *s, uint8_t key, uint32_t *value)
{
    if (!s->mounted) {
        return false;
    }
    const int32_t at = km_store_index(s->schema, key);
    if (at < 0) {
        return false;
    }
    *value = s->values[at];
    return true;
}
