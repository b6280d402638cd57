/* Commit, reset and idle compaction of the user-data store.
 *
 * Why each step is safe at a power cut is argued in docs/store.md; in short:
 *  - a record counts only once its commit cell (last, all zeros) is read
 *    back, so a cut mid-record leaves the previous state;
 *  - a page is compacted into a freshly erased page; the old page stays
 *    intact until it is itself the next target;
 *  - what a cut can leave half-done (a torn record, a torn snapshot) may read
 *    differently at each boot, so before the session acknowledges anything:
 *    suspect pages are erased, a page with unreadable cells after its last
 *    record is compacted away, and the first record restates the newest
 *    record of the previous session, so the state no longer depends on it. */
#include <string.h>

#include "km_store.h"
#include "km_store_internal.h"
#include "km_store_record.h"

static uint32_t prv_page_bit(uint32_t page)
{
    return 1u << page;
}

/* Erase and blank-check: a page counts as erased only if every cell reads
 * all ones after the erase. */
static bool prv_erase(km_store_t *s, uint32_t page)
{
    const km_flash_t *f = s->flash;
    s->erased &= ~prv_page_bit(page);
    s->suspect |= prv_page_bit(page);
    if (f->erase(f->ctx, page) != KM_FLASH_OK) {
        return false;
    }
    for (uint32_t off = 0; off < f->page_size; off += f->prog_size) {
        if (!km_rec_cell_erased(f, page * f->page_size + off)) {
            return false;
        }
    }
    s->erased |= prv_page_bit(page);
    s->suspect &= ~prv_page_bit(page);
    return true;
}

/* Programs a record one cell at a time: the body, then reads it back, then
 * the commit cell, then reads that back. */
static bool prv_write(km_store_t *s, uint32_t page, uint32_t offset, const uint8_t *rec,
                      uint32_t size)
{
    const km_flash_t *f = s->flash;
    const uint32_t c = f->prog_size;
    const uint32_t base = page * f->page_size + offset;
    uint8_t back[KM_REC_MAX_CELL];
    for (uint32_t at = 0; at < size; at += c) {
        if (at + c == size) {
            /* Commit cell: only after the whole body is known good. */
            for (uint32_t chk = 0; chk < at; chk += c) {
                if (f->read(f->ctx, base + chk, back, c) != KM_FLASH_OK ||
                    memcmp(back, &rec[chk], c) != 0) {
                    return false;
                }
            }
        }
        if (f->program(f->ctx, base + at, &rec[at], c) != KM_FLASH_OK) {
            return false;
        }
    }
    return f->read(f->ctx, base + size - c, back, c) == KM_FLASH_OK &&
           memcmp(back, &rec[size - c], c) == 0;
}

/* Writes state as a snapshot of generation gen+1 into the next page of the
 * ring, erased first unless this session already erased it. */
static bool prv_compact(km_store_t *s, const uint32_t *state)
{
    const km_flash_t *f = s->flash;
    const uint32_t target =
        (s->active == KM_STORE_NO_PAGE) ? 0u : ((uint32_t)s->active + 1u) % f->page_count;
    if ((s->erased & prv_page_bit(target)) == 0u && !prv_erase(s, target)) {
        return false;
    }
    s->erased &= ~prv_page_bit(target);
    uint8_t buf[KM_REC_MAX_BYTES];
    const km_rec_t hdr = {.type = KM_REC_SNAPSHOT,
                          .version = s->schema->version,
                          .gen = s->gen + 1u,
                          .hash = s->hash};
    const uint32_t size =
        km_rec_encode(buf, &hdr, s->schema, state, km_store_all_keys(s->schema), f->prog_size);
    if (!prv_write(s, target, 0u, buf, size)) {
        s->suspect |= prv_page_bit(target);
        return false;
    }
    s->active = (uint8_t)target;
    s->gen++;
    s->tail = size;
    s->last_keys = km_store_all_keys(s->schema);
    s->dirty = false;
    s->need_snapshot = false;
    s->restate = false;
    s->restate_snapshot = false;
    return true;
}

static bool prv_erase_suspects(km_store_t *s)
{
    for (uint32_t p = 0; p < s->flash->page_count; p++) {
        if ((s->suspect & prv_page_bit(p)) != 0u && !prv_erase(s, p)) {
            return false;
        }
    }
    return true;
}

/* Appends the change as one record, restating the previous session's newest
 * record on the session's first commit. */
static bool prv_append(km_store_t *s, const uint32_t *next, uint32_t changed)
{
    const km_flash_t *f = s->flash;
    km_rec_t hdr = {.type = KM_REC_DELTA,
                    .version = s->schema->version,
                    .gen = s->gen,
                    .hash = s->hash};
    uint8_t buf[KM_REC_MAX_BYTES];
    uint32_t mask = changed;
    if (s->restate && s->restate_snapshot) {
        /* The page's snapshot may be torn and read valid only by chance: a
         * copy of it (the old state, same generation) keeps the page valid
         * on its own. The change follows as a delta, so the next session
         * restates that small delta instead of copying the snapshot again. */
        hdr.type = KM_REC_SNAPSHOT;
        const uint32_t all = km_store_all_keys(s->schema);
        const uint32_t copy = km_rec_encode(buf, &hdr, s->schema, s->values, all, f->prog_size);
        uint32_t n = 0;
        for (uint32_t m = changed; m != 0u; m &= m - 1u) {
            n++;
        }
        const uint32_t after = km_rec_size(KM_REC_DELTA, n, f->prog_size);
        if (copy + after > f->page_size - s->tail) {
            return prv_compact(s, next);
        }
        if (!prv_write(s, s->active, s->tail, buf, copy)) {
            s->dirty = true;
            return false;
        }
        s->tail += copy;
        s->last_keys = all;
        s->restate = false;
        s->restate_snapshot = false;
        hdr.type = KM_REC_DELTA;
        if (mask == 0u) {
            /* Nothing changed: one key still follows, so the copy is not
             * the newest record and the next session need not copy it. */
            mask = 1u;
        }
    } else if (s->restate) {
        mask |= s->last_keys;
    }
    const uint32_t size = km_rec_encode(buf, &hdr, s->schema, next, mask, f->prog_size);
    if (size > f->page_size - s->tail) {
        return prv_compact(s, next);
    }
    if (!prv_write(s, s->active, s->tail, buf, size)) {
        /* The record may be half there: never append after it, and put the
         * old state back in a fresh page now if the flash lets us. */
        s->dirty = true;
        (void)prv_compact(s, s->values);
        return false;
    }
    s->tail += size;
    s->last_keys = mask;
    s->restate = false;
    s->restate_snapshot = false;
    return true;
}

/* True if a later mount could show another state than RAM holds: a torn
 * record or page from a past cut, which a read may find valid or not, has
 * not been settled by a write in this session yet. An acknowledgement must
 * be durable for the whole state, so even an unchanged commit then writes
 * (once per session at most; a session that commits nothing writes nothing). */
static bool prv_in_doubt(const km_store_t *s)
{
    return s->dirty || s->suspect != 0u || s->restate;
}

static km_store_status_t prv_commit_state(km_store_t *s, const uint32_t *next)
{
    uint32_t changed = 0;
    for (uint32_t i = 0; i < s->schema->count; i++) {
        if (next[i] != s->values[i]) {
            changed |= 1u << i;
        }
    }
    if (changed == 0u && !prv_in_doubt(s)) {
        return KM_STORE_OK;
    }
    s->wrote = true;
    bool ok = prv_erase_suspects(s);
    if (ok) {
        if (s->active == KM_STORE_NO_PAGE || s->dirty || s->need_snapshot) {
            ok = prv_compact(s, next);
        } else {
            ok = prv_append(s, next, changed);
        }
    }
    if (!ok) {
        return KM_STORE_ERR_FLASH;
    }
    memcpy(s->values, next, s->schema->count * sizeof next[0]);
    return KM_STORE_OK;
}

km_store_status_t km_store_commit(km_store_t *s, const uint8_t *keys, const uint32_t *values,
                                  uint32_t n)
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
    if (!s->mounted || !s->wrote) {
        return false; /* a session that commits nothing touches no flash */
    }
    const km_flash_t *f = s->flash;
    for (uint32_t p = 0; p < f->page_count; p++) {
        if ((s->suspect & prv_page_bit(p)) != 0u) {
            (void)prv_erase(s, p);
            return true;
        }
    }
    if (s->active == KM_STORE_NO_PAGE) {
        return false;
    }
    /* Keep room for the largest record (a snapshot copy or a full reset) so
     * a commit does not wait on an erase. */
    const uint32_t room = km_rec_size(KM_REC_SNAPSHOT, s->schema->count, f->prog_size);
    if (!s->dirty && !s->need_snapshot && f->page_size - s->tail >= room) {
        return false;
    }
    const uint32_t target = ((uint32_t)s->active + 1u) % f->page_count;
    if ((s->erased & prv_page_bit(target)) == 0u) {
        (void)prv_erase(s, target);
    } else {
        (void)prv_compact(s, s->values);
    }
    return true;
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
