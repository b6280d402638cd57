/* Mount: find the newest valid snapshot, replay its page, and note what the
 * first commit of the session must repair. Reads only: a boot that commits
 * nothing leaves the flash untouched. */
#include <string.h>

#include "km_crc32.h"
#include "km_store.h"
#include "km_store_internal.h"
#include "km_store_record.h"

typedef struct {
    bool erased;          /* every cell reads all ones */
    bool has_snapshot;
    uint16_t version;     /* of the last valid snapshot */
    uint32_t gen;
    uint32_t hash;
    uint32_t valid_end;   /* byte after the last valid record */
    uint32_t used_end;    /* byte after the last cell that is not erased */
    uint8_t last_type;
    uint32_t last_keys;
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

/* Applies a record's entries whose keys the schema still has; returns the
 * bitmap of those keys. Keys dropped from the schema are ignored. */
static uint32_t prv_apply(const km_store_schema_t *schema, const km_rec_t *rec, uint32_t *values,
                          bool apply)
{
    uint32_t mask = 0;
    for (uint32_t i = 0; i < rec->count; i++) {
        const int32_t at = km_store_index(schema, km_rec_key(rec, i));
        if (at >= 0) {
            mask |= 1u << (uint32_t)at;
            if (apply) {
                values[at] = km_rec_value(rec, i);
            }
        }
    }
    return mask;
}

/* Walks a page record by record. A cell that starts no valid record is
 * skipped one cell at a time, never trusted. values becomes the page's
 * state: its last valid snapshot plus the valid deltas after it. Each page
 * is read once: a torn cell may read differently at each read, so the
 * choice of page and its state must come from the same reads. */
static void prv_scan(const km_store_t *s, uint32_t page, prv_page_t *pi, uint32_t *values)
{
    const km_flash_t *f = s->flash;
    uint8_t buf[KM_REC_MAX_BYTES];
    km_rec_t rec;
    memset(pi, 0, sizeof *pi);
    pi->erased = true;
    uint32_t off = 0;
    while (off < f->page_size) {
        if (km_rec_read(f, page, off, buf, &rec) &&
            (rec.type == KM_REC_SNAPSHOT || pi->has_snapshot)) {
            if (rec.type == KM_REC_SNAPSHOT) {
                pi->has_snapshot = true;
                pi->gen = rec.gen;
                pi->version = rec.version;
                pi->hash = rec.hash;
                prv_defaults(s->schema, values);
            }
            /* Another schema version: the values mean something else. */
            const bool same = (pi->version == s->schema->version);
            pi->last_keys = prv_apply(s->schema, &rec, values, same);
            pi->last_type = rec.type;
            pi->erased = false;
            off += rec.size;
            pi->valid_end = off;
            pi->used_end = off;
        } else {
            if (!km_rec_cell_erased(f, page * f->page_size + off)) {
                pi->erased = false;
                pi->used_end = off + f->prog_size;
            }
            off += f->prog_size;
        }
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
    /* Room for a snapshot, its restated copy and some deltas. */
    return f->page_size >= 3u * km_rec_size(KM_REC_SNAPSHOT, schema->count, c);
}

km_store_mount_t km_store_mount(km_store_t *s, const km_flash_t *flash,
                                const km_store_schema_t *schema, uint32_t *values_out)
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
    prv_page_t pi;
    prv_page_t best;
    uint32_t cand[KM_STORE_MAX_KEYS];
    memset(&best, 0, sizeof best);
    for (uint32_t p = 0; p < flash->page_count; p++) {
        prv_defaults(schema, cand);
        prv_scan(s, p, &pi, cand);
        if (pi.has_snapshot) {
            if (s->active == KM_STORE_NO_PAGE || pi.gen > s->gen) {
                s->active = (uint8_t)p;
                s->gen = pi.gen;
                best = pi;
                memcpy(s->values, cand, schema->count * sizeof cand[0]);
            }
        } else {
            /* May hold a torn snapshot that a later read finds valid, even
             * if it reads erased now (a cut erase leaves weak cells):
             * erased before the session acknowledges anything. */
            s->suspect |= 1u << p;
        }
        all_erased = all_erased && pi.erased;
    }

    km_store_mount_t result;
    if (s->active == KM_STORE_NO_PAGE) {
        result = all_erased ? KM_STORE_MOUNT_DEFAULTS_BLANK : KM_STORE_MOUNT_DEFAULTS_INVALID;
    } else {
        pi = best;
        /* The cell after the last valid record may be the first cell of a
         * record a cut tore: weak, it can read erased now and not later, and
         * on the G0 its ECC may be partly written. Never program it: the
         * session starts one cell further. */
        s->tail = pi.valid_end + flash->prog_size;
        if (s->tail > flash->page_size) {
            s->tail = flash->page_size;
        }
        /* Compact first if a torn record follows the last valid one, or if
         * the next page of the ring (the only one a compaction from this
         * page writes a higher generation into) is in doubt: it then gets
         * the new snapshot, which also ends the doubt for later sessions. */
        const uint32_t next = ((uint32_t)s->active + 1u) % flash->page_count;
        s->dirty = pi.used_end > pi.valid_end || (s->suspect & (1u << next)) != 0u;
        s->restate = true;
        s->restate_snapshot = (pi.last_type == KM_REC_SNAPSHOT);
        s->last_keys = pi.last_keys;
        if (pi.version != schema->version) {
            result = KM_STORE_MOUNT_DEFAULTS_SCHEMA;
            s->need_snapshot = true;
        } else if (pi.hash != s->hash) {
            result = KM_STORE_MOUNT_MIGRATED;
            s->need_snapshot = true;
        } else {
            result = KM_STORE_MOUNT_LOADED;
        }
    }
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
