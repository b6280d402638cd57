/* SPDX-License-Identifier: Apache-2.0 */
/* km_store_peek (km_store_peek.h): the mount's page choice and replay, reads only, each record read once. */
#include "km_store_peek.h"

#include <string.h>

#include "km_store.h"
#include "km_store_record.h"

#define PRV_MAX 4u

/* Sets the value of `key` if it is one of keys[]. */
static void prv_set(const uint8_t *keys, uint32_t n, uint32_t *v, uint8_t key, uint32_t value)
{
    for (uint32_t i = 0; i < n; i++) {
        if (keys[i] == key) {
            v[i] = value;
        }
    }
}

/* keys[]'s values on page p, whose snapshot is *rec, into cand: the
 * snapshot's, then every delta's, deltas only after a K that reads
 * programmed (docs/store.md). One loop over the records, the snapshot
 * first (off 0). Reads over rec and buf. */
static void prv_replay(const km_flash_t *f, uint32_t p, km_rec_t *rec, uint8_t *buf, const uint8_t *keys,
                       uint32_t n, uint32_t *cand, uint8_t *snap_keys)
{
    const uint32_t snap_count = rec->count;
    uint32_t off = 0u;
    for (;;) {
        uint32_t at = 0u;
        for (uint32_t i = 0; i < rec->count; i++) {
            uint8_t id;
            uint32_t v;
            bool indexed;
            km_rec_entry(rec, &at, &id, &v, &indexed);
            if (off == 0u) {
                snap_keys[i] = id;
            } else if (indexed) {
                if (id >= snap_count) {
                    continue;
                }
                id = snap_keys[id];
            }
            prv_set(keys, n, cand, id, v);
        }
        if (off == 0u) {
            off = rec->size;
            if (km_rec_cell_erased(f, p * f->page_size + off)) {
                return;
            }
            off += f->prog_size;
        } else {
            off += rec->size;
        }
        if (off >= f->page_size || !km_rec_read(f, p, off, buf, rec) || rec->type == KM_REC_SNAPSHOT) {
            return;
        }
    }
}

bool km_store_peek(const km_flash_t *f, uint16_t version, const uint8_t *keys, uint32_t n, uint32_t *values)
{
    uint8_t buf[KM_REC_MAX_BYTES];
    uint8_t snap_keys[KM_STORE_MAX_KEYS];
    uint32_t best[PRV_MAX];
    bool found = false;
    bool same = false;
    uint32_t best_gen = 0u;
    if (n > PRV_MAX) {
        return false;
    }
    memset(snap_keys, 0, sizeof snap_keys); /* filled below; said for -fanalyzer */
    memset(best, 0, sizeof best);
    for (uint32_t p = 0; p < f->page_count; p++) {
        km_rec_t rec;
        /* The mount keeps the first page of the highest generation. */
        if (!km_rec_read(f, p, 0u, buf, &rec) || rec.type != KM_REC_SNAPSHOT ||
            (found && rec.gen <= best_gen)) {
            continue;
        }
        found = true;
        best_gen = rec.gen;
        same = rec.version == version; /* else the values mean something else */
        if (same) {
            memcpy(best, values, n * sizeof best[0]);
            prv_replay(f, p, &rec, buf, keys, n, best, snap_keys);
        }
    }
    if (!found || !same) {
        return false;
    }
    memcpy(values, best, n * sizeof best[0]);
    return true;
}
