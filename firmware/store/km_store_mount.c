/* SPDX-License-Identifier: Apache-2.0 */
/* Mount: find the newest valid snapshot, replay its page, and choose the
 * page the session's first commit will erase. Reads only: a boot that
 * commits nothing leaves the flash untouched. */
#include <string.h>

#include "km_crc32.h"
#include "km_store.h"
#include "km_store_internal.h"
#include "km_store_record.h"

typedef struct {
    bool valid;     /* the snapshot at offset 0 reads valid */
    bool confirmed; /* ... and its confirmation cell K reads programmed */
    bool erased;    /* no valid snapshot and every cell reads all ones */
    uint16_t version;
    uint32_t gen;
    uint32_t hash;
} prv_page_t;

int32_t km_store_index(const km_store_schema_t *schema, uint8_t key)
{
    for (uint32_t i = 0; i < schema->count; i++) {
        if (schema->keys[i].key == key) {
            return (int32_t)i;
        }
    }
    return -1;
}

uint32_t km_store_all_keys(const km_store_schema_t *schema)
{
    return (schema->count >= 32u) ? 0xFFFFFFFFu : ((1u << schema->count) - 1u);
}

static void prv_defaults(const km_store_schema_t *schema, uint32_t *values)
{
    for (uint32_t i = 0; i < schema->count; i++) {
        values[i] = schema->keys[i].def;
    }
}

/* Applies a record's entries whose keys the schema still has (apply false: none). */
static void prv_apply(const km_store_schema_t *schema, const km_rec_t *rec, uint32_t *values, bool apply,
                      const uint8_t *snap_keys, uint32_t snap_count)
{
    uint32_t at = 0;
    for (uint32_t i = 0; apply && i < rec->count; i++) {
        uint8_t id;
        uint32_t v;
        bool indexed;
        km_rec_entry(rec, &at, &id, &v, &indexed);
        if (indexed) {
            if (id >= snap_count) {
                continue;
            }
            id = snap_keys[id];
        }
        const int32_t where = km_store_index(schema, id);
        if (where >= 0) {
            values[where] = v;
        }
    }
}

/* Reads a page once: its snapshot, its K and, under a confirmed snapshot, its valid deltas. */
static void prv_scan(const km_store_t *s, uint32_t page, prv_page_t *pi, uint32_t *values)
{
    const km_flash_t *f = s->flash;
    const uint32_t base = page * f->page_size;
    uint8_t buf[KM_REC_MAX_BYTES];
    km_rec_t rec;
    pi->valid = false;
    pi->confirmed = false;
    pi->erased = false;
    if (!km_rec_read(f, page, 0u, buf, &rec) || rec.type != KM_REC_SNAPSHOT) {
        pi->erased = km_rec_range_erased(f, base, f->page_size);
        return;
    }
    pi->valid = true;
    pi->gen = rec.gen;
    pi->version = rec.version;
    pi->hash = rec.hash;
    uint8_t snap_keys[KM_STORE_MAX_KEYS];
    memset(snap_keys, 0, sizeof snap_keys); /* filled below; said for -fanalyzer */
    const uint32_t snap_count = rec.count;
    uint32_t at = 0;
    for (uint32_t i = 0; i < snap_count; i++) {
        uint32_t v;
        bool indexed;
        km_rec_entry(&rec, &at, &snap_keys[i], &v, &indexed);
    }
    /* Another schema version: the values mean something else. */
    const bool same = (rec.version == s->schema->version);
    prv_apply(s->schema, &rec, values, same, snap_keys, snap_count);
    uint32_t off = rec.size;
    /* A K that does not read erased proves the snapshot solid. */
    pi->confirmed = !km_rec_cell_erased(f, base + off);
    if (!pi->confirmed) {
        return;
    }
    off += f->prog_size;
    while (off < f->page_size && km_rec_read(f, page, off, buf, &rec) && rec.type != KM_REC_SNAPSHOT) {
        prv_apply(s->schema, &rec, values, same, snap_keys, snap_count);
        off += rec.size;
    }
}

static bool prv_geometry_ok(const km_flash_t *f, const km_store_schema_t *schema)
{
    if (f == NULL || schema == NULL || schema->keys == NULL || schema->count == 0u ||
        schema->count > KM_STORE_MAX_KEYS) {
        return false;
    }
    for (uint32_t i = 0; i < schema->count; i++) {
        if (km_store_index(schema, schema->keys[i].key) != (int32_t)i) {
            return false; /* repeated key */
        }
    }
    const uint32_t c = f->prog_size;
    if ((c != 2u && c != 4u && c != 8u) || f->page_size % c != 0u || f->page_count < 2u ||
        f->page_count > KM_STORE_MAX_PAGES) {
        return false;
    }
    /* Room for a snapshot, K and at least a full-state delta after it. */
    return f->page_size >= 3u * km_rec_snapshot_size(schema->count, c);
}

/* The page the session's first commit erases and writes into (docs/store.md "Why every cut is safe"). */
static uint8_t prv_target(uint32_t pages, uint8_t active, bool confirmed, uint32_t valid, uint8_t anchor)
{
    /* pages >= 2 after the geometry check; said again for the analyzers,
     * which cannot see that s->values never aliases the flash's page count. */
    if (active == KM_STORE_NO_PAGE || pages == 0u) {
        return 0u;
    }
    uint32_t t = (uint32_t)active + 1u < pages ? (uint32_t)active + 1u : 0u;
    if (confirmed || (valid & ~(1u << active)) == 0u) {
        return (uint8_t)t;
    }
    if (pages == 2u) {
        return active;
    }
    while (t == active || t == anchor) {
        t = t + 1u < pages ? t + 1u : 0u;
    }
    return (uint8_t)t;
}

/* What the mount found: the active page's values with this schema, the
 * defaults (a blank store, no valid page, or another schema's values), or
 * this schema's keys migrated from another key set (hash). */
static km_store_mount_t prv_result(const km_store_t *s, const prv_page_t *best, bool all_erased)
{
    if (s->active == KM_STORE_NO_PAGE) {
        return all_erased ? KM_STORE_MOUNT_DEFAULTS_BLANK : KM_STORE_MOUNT_DEFAULTS_INVALID;
    }
    if (best->version != s->schema->version) {
        return KM_STORE_MOUNT_DEFAULTS_SCHEMA;
    }
    return best->hash != s->hash ? KM_STORE_MOUNT_MIGRATED : KM_STORE_MOUNT_LOADED;
}

km_store_mount_t km_store_mount(km_store_t *s, const km_flash_t *flash, const km_store_schema_t *schema,
                                uint32_t *values_out)
{
    memset(s, 0, sizeof *s);
    s->active = KM_STORE_NO_PAGE;
    if (!prv_geometry_ok(flash, schema)) {
        return KM_STORE_MOUNT_ERR_ARG;
    }
    s->flash = flash;
    s->schema = schema;
    for (uint32_t i = 0; i < schema->count; i++) {
        s->hash = km_crc32(s->hash, &schema->keys[i].key, 1u);
    }
    prv_defaults(schema, s->values);

    bool all_erased = true;
    uint32_t valid = 0;
    uint8_t anchor = KM_STORE_NO_PAGE; /* highest-generation confirmed page */
    uint32_t anchor_gen = 0;
    prv_page_t pi;
    prv_page_t best;
    uint32_t cand[KM_STORE_MAX_KEYS];
    memset(&best, 0, sizeof best);
    for (uint32_t p = 0; p < flash->page_count; p++) {
        prv_defaults(schema, cand);
        prv_scan(s, p, &pi, cand);
        if (pi.valid) {
            valid |= 1u << p;
            if (s->active == KM_STORE_NO_PAGE || pi.gen > s->gen) {
                s->active = (uint8_t)p;
                s->gen = pi.gen;
                best = pi;
                memcpy(s->values, cand, schema->count * sizeof cand[0]);
            }
            if (pi.confirmed && (anchor == KM_STORE_NO_PAGE || pi.gen > anchor_gen)) {
                anchor = (uint8_t)p;
                anchor_gen = pi.gen;
            }
        } else {
            /* May hold a torn snapshot: erased before the session acknowledges anything. */
            s->suspect |= 1u << p;
        }
        all_erased = all_erased && pi.erased;
    }
    s->target = prv_target(flash->page_count, s->active, best.confirmed, valid, anchor);
    const km_store_mount_t result = prv_result(s, &best, all_erased);
    s->mounted = true;
    if (values_out != NULL) {
        memcpy(values_out, s->values, schema->count * sizeof s->values[0]);
    }
    return result;
}

bool km_store_mount_is_defaults(km_store_mount_t m)
{
    return m == KM_STORE_MOUNT_DEFAULTS_BLANK || m == KM_STORE_MOUNT_DEFAULTS_INVALID ||
           m == KM_STORE_MOUNT_DEFAULTS_SCHEMA;
}
