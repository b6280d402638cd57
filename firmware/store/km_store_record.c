/* SPDX-License-Identifier: Apache-2.0 */
/* Encoding and checking of store records: the only code that knows the bytes. */
#include "km_store_record.h"

#include <string.h>

#include "km_crc32.h"

#define PRV_DENSE_MASK 0xE0u /* a dense tag is 0b100c_cccc: count - 1 in the low five bits */
#define PRV_IDX_LEN_SHIFT 5u

/* prv_put32 a call in the 32 KiB build (its compact protocol, KM_PROTOCOL_COMPACT: docs/footprint.md). */
#if defined(KM_PROTOCOL_COMPACT) && KM_PROTOCOL_COMPACT
#define PRV_PUT32_INLINE __attribute__((noinline))
#else
#define PRV_PUT32_INLINE
#endif

/* n rounded up to a whole number of cells: a mask for a power-of-two cell
 * (every board's), no library division (km_store_maintain runs each idle pass). */
static uint32_t prv_round_up(uint32_t n, uint32_t cell)
{
    if ((cell & (cell - 1u)) == 0u) {
        return (n + cell - 1u) & (0u - cell);
    }
    return (n + cell - 1u) / cell * cell;
}

static PRV_PUT32_INLINE void prv_put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static uint32_t prv_get(const uint8_t *p, uint32_t len)
{
    uint32_t v = 0;
    for (uint32_t i = len; i > 0u; i--) {
        v = (v << 8) | p[i - 1u];
    }
    return v;
}

/* Fewest bytes that hold v (at least one). */
static uint32_t prv_value_len(uint32_t v)
{
    uint32_t len = 1;
    while (len < 4u && (v >> (8u * len)) != 0u) {
        len++;
    }
    return len;
}

uint32_t km_rec_snapshot_size(uint32_t count, uint32_t cell)
{
    return prv_round_up(KM_REC_HDR_SNAPSHOT + count * KM_REC_ENTRY + KM_REC_CRC, cell) + cell;
}

uint32_t km_rec_delta_max_size(uint32_t count, uint32_t cell)
{
    return prv_round_up(1u + count * (1u + 4u) + KM_REC_CRC, cell);
}

/* Pads buf[at..) with 0xFF to end - 4 and puts the CRC of buf[0..end-4) there. */
static void prv_seal(uint8_t *buf, uint32_t at, uint32_t end)
{
    memset(&buf[at], 0xFF, end - KM_REC_CRC - at);
    prv_put32(&buf[end - KM_REC_CRC], km_crc32(0u, buf, end - KM_REC_CRC));
}

uint32_t km_rec_encode(uint8_t *buf, const km_rec_t *rec, const km_store_schema_t *schema,
                       const uint32_t *values, uint32_t keys_mask, uint32_t cell)
{
    const bool snap = (rec->type == KM_REC_SNAPSHOT);
    uint32_t count = 0;
    uint32_t at = snap ? KM_REC_HDR_SNAPSHOT : 1u;
    for (uint32_t i = 0; i < schema->count; i++) {
        if ((keys_mask & (1u << i)) == 0u) {
            continue;
        }
        /* Snapshot: key, 4-byte value; dense: index and length, the value's fewest bytes. */
        const uint32_t len = snap ? 4u : prv_value_len(values[i]);
        buf[at] = snap ? schema->keys[i].key : (uint8_t)(i | ((len - 1u) << PRV_IDX_LEN_SHIFT));
        prv_put32(&buf[at + 1u], values[i]); /* a dense entry's bytes past len are overwritten next */
        at += 1u + len;
        count++;
    }
    if (!snap) {
        /* count >= 1: a delta carries at least one change. */
        buf[0] = (uint8_t)(KM_REC_DELTA | (count - 1u));
        const uint32_t size = prv_round_up(at + KM_REC_CRC, cell);
        prv_seal(buf, at, size);
        return size;
    }
    const uint32_t size = km_rec_snapshot_size(count, cell);
    buf[0] = KM_REC_SNAPSHOT;
    buf[1] = (uint8_t)count;
    buf[2] = (uint8_t)rec->version;
    buf[3] = (uint8_t)(rec->version >> 8);
    prv_put32(&buf[4], rec->gen);
    prv_put32(&buf[8], rec->hash);
    prv_seal(buf, at, size - cell);
    memset(&buf[size - cell], 0x00, cell);
    return size;
}

typedef struct {
    const km_flash_t *f;
    uint32_t addr; /* of the record */
    uint32_t room; /* bytes from the record to the end of its page */
    uint32_t have; /* bytes read so far, whole cells */
    uint8_t *buf;
} prv_reader_t;

/* Makes sure the first n bytes of the record are in buf, reading only the
 * cells that hold them. */
static bool prv_need(prv_reader_t *r, uint32_t n)
{
    if (n <= r->have) {
        return true;
    }
    const uint32_t to = prv_round_up(n, r->f->prog_size);
    if (to > r->room || to > KM_REC_MAX_BYTES ||
        r->f->read(r->f->ctx, r->addr + r->have, &r->buf[r->have], to - r->have) != KM_FLASH_OK) {
        return false;
    }
    r->have = to;
    return true;
}

/* Dense delta: walks its count entries to where they end (*end). */
static bool prv_dense_end(prv_reader_t *r, uint32_t count, uint32_t *end)
{
    const uint8_t *b = r->buf;
    uint32_t at = 1;
    uint32_t next_idx = 0; /* indices strictly increase */
    for (uint32_t i = 0; i < count; i++) {
        if (!prv_need(r, at + 1u)) {
            return false;
        }
        const uint8_t e = b[at];
        const uint32_t idx = e & 0x1Fu;
        if ((e & 0x80u) != 0u || idx < next_idx) {
            return false;
        }
        next_idx = idx + 1u;
        at += 1u + ((uint32_t)e >> PRV_IDX_LEN_SHIFT) + 1u;
    }
    *end = at;
    return true;
}

/* Where a record's fixed bytes are: [from, to) must all read `fill`, its CRC-32 is at crc_at. */
typedef struct {
    uint32_t hdr; /* entries start here */
    uint32_t size;
    uint32_t crc_at;
    uint32_t from;
    uint32_t to;
    uint8_t fill;
} prv_layout_t;

/* Dense delta: 0xFF padding from its entries' end to the CRC in the last four bytes. Snapshot or legacy
 * delta: fixed-size entries, CRC, then the commit cell of zeros. */
static bool prv_layout(prv_reader_t *r, uint8_t type, uint32_t count, prv_layout_t *l)
{
    const uint32_t c = r->f->prog_size;
    if ((type & PRV_DENSE_MASK) == KM_REC_DELTA) {
        uint32_t at;
        if (!prv_dense_end(r, count, &at)) {
            return false;
        }
        l->hdr = 1u;
        l->size = prv_round_up(at + KM_REC_CRC, c);
        l->crc_at = l->size - KM_REC_CRC;
        l->from = at;
        l->to = l->crc_at;
        l->fill = 0xFFu;
        return true;
    }
    if (count > KM_STORE_MAX_KEYS || (type == KM_REC_DELTA_LEGACY && count == 0u)) {
        return false;
    }
    l->hdr = (type == KM_REC_SNAPSHOT) ? KM_REC_HDR_SNAPSHOT : KM_REC_HDR_LEGACY;
    l->size = prv_round_up(l->hdr + count * KM_REC_ENTRY + KM_REC_CRC, c) + c;
    l->crc_at = l->size - c - KM_REC_CRC;
    l->from = l->size - c;
    l->to = l->size;
    l->fill = 0x00u;
    return true;
}

bool km_rec_read(const km_flash_t *f, uint32_t page, uint32_t offset, uint8_t *buf, km_rec_t *rec)
{
    prv_reader_t r = {f, page * f->page_size + offset, 0u, 0u, buf};
    if (offset >= f->page_size) {
        return false;
    }
    r.room = f->page_size - offset;
    if (!prv_need(&r, 1u)) {
        return false;
    }
    const uint8_t type = buf[0];
    const bool dense = (type & PRV_DENSE_MASK) == KM_REC_DELTA;
    if (!dense && type != KM_REC_SNAPSHOT && type != KM_REC_DELTA_LEGACY) {
        return false;
    }
    const uint32_t count = dense ? (type & ~PRV_DENSE_MASK) + 1u : buf[1];
    prv_layout_t l;
    if (!prv_layout(&r, type, count, &l) || !prv_need(&r, l.size)) {
        return false;
    }
    for (uint32_t i = l.from; i < l.to; i++) {
        if (buf[i] != l.fill) {
            return false;
        }
    }
    if (km_crc32(0u, buf, l.crc_at) != prv_get(&buf[l.crc_at], KM_REC_CRC)) {
        return false;
    }
    rec->type = dense ? (uint8_t)KM_REC_DELTA : type;
    rec->count = (uint8_t)count;
    rec->size = l.size;
    rec->entries = &buf[l.hdr];
    if (type == KM_REC_SNAPSHOT) {
        rec->version = (uint16_t)prv_get(&buf[2], 2u);
        rec->gen = prv_get(&buf[4], 4u);
        rec->hash = prv_get(&buf[8], 4u);
    }
    return true;
}

void km_rec_entry(const km_rec_t *rec, uint32_t *at, uint8_t *id, uint32_t *value, bool *indexed)
{
    const uint8_t *e = &rec->entries[*at];
    if (rec->type == KM_REC_DELTA) {
        const uint32_t len = ((uint32_t)e[0] >> PRV_IDX_LEN_SHIFT) + 1u;
        *id = (uint8_t)(e[0] & 0x1Fu);
        *value = prv_get(&e[1], len);
        *indexed = true;
        *at += 1u + len;
    } else {
        *id = e[0];
        *value = prv_get(&e[1], 4u);
        *indexed = false;
        *at += KM_REC_ENTRY;
    }
}

bool km_rec_cell_erased(const km_flash_t *f, uint32_t addr)
{
    return km_rec_range_erased(f, addr, f->prog_size);
}

bool km_rec_range_erased(const km_flash_t *f, uint32_t addr, uint32_t len)
{
    uint8_t chunk[4u * KM_REC_MAX_CELL];
    while (len > 0u) {
        const uint32_t n = (len < sizeof chunk) ? len : (uint32_t)sizeof chunk;
        if (f->read(f->ctx, addr, chunk, n) != KM_FLASH_OK) {
            return false;
        }
        for (uint32_t i = 0; i < n; i++) {
            if (chunk[i] != 0xFFu) {
                return false;
            }
        }
        addr += n;
        len -= n;
    }
    return true;
}
