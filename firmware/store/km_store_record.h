/* On-flash record format of the store (docs/store.md has the byte layout).
 *
 * A record is a body of whole cells, then one commit cell of all zero bytes:
 *   body  = header, entries (key u8, value u32 LE), 0xFF padding, CRC-32
 *   snapshot header: 'S', count, schema version u16, generation u32, key hash u32
 *   delta header:    'D', count, 0x00, 0x00
 * The commit cell is programmed last, after the body is read back, so a
 * record is valid only if its CRC matches and its commit cell reads zeros. */
#ifndef KM_STORE_RECORD_H
#define KM_STORE_RECORD_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"
#include "km_store.h"

#define KM_REC_SNAPSHOT 0x53u
#define KM_REC_DELTA 0x44u
#define KM_REC_HDR_SNAPSHOT 12u
#define KM_REC_HDR_DELTA 4u
#define KM_REC_ENTRY 5u
#define KM_REC_CRC 4u
#define KM_REC_MAX_CELL 8u
#define KM_REC_MAX_BYTES \
    (KM_REC_HDR_SNAPSHOT + KM_STORE_MAX_KEYS * KM_REC_ENTRY + KM_REC_CRC + 2u * KM_REC_MAX_CELL)

typedef struct {
    uint8_t type;
    uint8_t count;
    uint16_t version;        /* snapshot only */
    uint32_t gen;            /* snapshot only */
    uint32_t hash;           /* snapshot only */
    uint32_t size;           /* bytes, commit cell included */
    const uint8_t *entries;  /* count entries of KM_REC_ENTRY bytes */
} km_rec_t;

/* Bytes a record of count entries takes with cells of cell bytes. */
uint32_t km_rec_size(uint8_t type, uint32_t count, uint32_t cell);

/* Builds in buf the record of the keys in keys_mask (schema indices) with
 * their values; rec gives type, version, gen and hash. Returns its size. */
uint32_t km_rec_encode(uint8_t *buf, const km_rec_t *rec, const km_store_schema_t *schema,
                       const uint32_t *values, uint32_t keys_mask, uint32_t cell);

/* Reads the record at byte offset of page into buf. Returns true and fills
 * rec if it is whole: known type, inside the page, no ECC error, CRC good,
 * commit cell zero. */
bool km_rec_read(const km_flash_t *f, uint32_t page, uint32_t offset, uint8_t *buf, km_rec_t *rec);

/* The key and value of entry i of a valid record. */
uint8_t km_rec_key(const km_rec_t *rec, uint32_t i);
uint32_t km_rec_value(const km_rec_t *rec, uint32_t i);

/* Reads one cell; true if it reads all ones without ECC error. */
bool km_rec_cell_erased(const km_flash_t *f, uint32_t addr);

/* Reads len bytes from addr (whole cells) a few cells per read; true if
 * every cell reads all ones without ECC error. */
bool km_rec_range_erased(const km_flash_t *f, uint32_t addr, uint32_t len);

#endif
