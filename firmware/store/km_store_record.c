/* Encoding and checking of store records: the only code that knows the bytes. */
#include "km_store_record.h"

#include <string.h>

#include "km_crc32.h"

static uint32_t prv_round_up(uint32_t n, uint32_t cell)
{
    return (n + cell - 1u) / cell * cell;
}

static void prv_put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static uint32_t prv_get32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

static uint32_t prv_hdr_size(uint8_t type)
{
    return (type == KM_REC_SNAPSHOT) ? KM_REC_HDR_SNAPSHOT : KM_REC_HDR_DELTA;
}

uint32_t km_rec_size(uint8_t type, uint32_t count, uint32_t cell)
{
    const uint32_t body = prv_round_up(prv_hdr_size(type) + count * KM_REC_ENTRY + KM_REC_CRC, cell);
    return body + cell;
}

uint32_t km_rec_encode(uint8_t *buf, const km_rec_t *rec, const km_store_schema_t *schema,
                       const uint32_t *values, uint32_t keys_mask, uint32_t cell)
{
    uint32_t count = 0;
    uint32_t at = prv_hdr_size(rec->type);
    for (uint32_t i = 0; i < schema->count; i++) {
        if ((keys_mask & (1u << i)) != 0u) {
            buf[at] = schema->keys[i].key;
            prv_put32(&buf[at + 1u], values[i]);
            at += KM_REC_ENTRY;
            count++;
        }
    }
    const uint32_t size = km_rec_size(rec->type, count, cell);
    const uint32_t crc_at = size - cell - KM_REC_CRC;
    buf[0] = rec->type;
    buf[1] = (uint8_t)count;
    if (rec->type == KM_REC_SNAPSHOT) {
        buf[2] = (uint8_t)rec->version;
        buf[3] = (uint8_t)(rec->version >> 8);
        prv_put32(&buf[4], rec->gen);
        prv_put32(&buf[8], rec->hash);
    } else {
        buf[2] = 0u;
        buf[3] = 0u;
    }
    memset(&buf[at], 0xFF, crc_at - at);
    prv_put32(&buf[crc_at], km_crc32(0u, buf, crc_at));
    memset(&buf[size - cell], 0x00, cell);
    return size;
}

bool km_rec_read(const km_flash_t *f, uint32_t page, uint32_t offset, uint8_t *buf, km_rec_t *rec)
{
    const uint32_t cell = f->prog_size;
    const uint32_t base = page * f->page_size;
    if (offset + cell > f->page_size || f->read(f->ctx, base + offset, buf, cell) != KM_FLASH_OK) {
        return false;
    }
    const uint8_t type = buf[0];
    const uint8_t count = buf[1];
    if ((type != KM_REC_SNAPSHOT && type != KM_REC_DELTA) || count > KM_STORE_MAX_KEYS ||
        (type == KM_REC_DELTA && count == 0u)) {
        return false;
    }
    const uint32_t size = km_rec_size(type, count, cell);
    if (size > f->page_size - offset ||
        f->read(f->ctx, base + offset + cell, &buf[cell], size - cell) != KM_FLASH_OK) {
        return false;
    }
    for (uint32_t i = size - cell; i < size; i++) {
        if (buf[i] != 0x00u) {
            return false;
        }
    }
    const uint32_t crc_at = size - cell - KM_REC_CRC;
    if (km_crc32(0u, buf, crc_at) != prv_get32(&buf[crc_at])) {
        return false;
    }
    rec->type = type;
    rec->count = count;
    rec->size = size;
    rec->entries = &buf[prv_hdr_size(type)];
    if (type == KM_REC_SNAPSHOT) {
        rec->version = (uint16_t)(buf[2] | (buf[3] << 8));
        rec->gen = prv_get32(&buf[4]);
        rec->hash = prv_get32(&buf[8]);
    } else {
        rec->version = 0u;
        rec->gen = 0u;
        rec->hash = 0u;
    }
    return true;
}

uint8_t km_rec_key(const km_rec_t *rec, uint32_t i)
{
    return rec->entries[i * KM_REC_ENTRY];
}

uint32_t km_rec_value(const km_rec_t *rec, uint32_t i)
{
    return prv_get32(&rec->entries[i * KM_REC_ENTRY + 1u]);
}

bool km_rec_cell_erased(const km_flash_t *f, uint32_t addr)
{
    uint8_t cell[KM_REC_MAX_CELL];
    if (f->read(f->ctx, addr, cell, f->prog_size) != KM_FLASH_OK) {
        return false;
    }
    for (uint32_t i = 0; i < f->prog_size; i++) {
        if (cell[i] != 0xFFu) {
            return false;
        }
    }
    return true;
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
