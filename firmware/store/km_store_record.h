/* SPDX-License-Identifier: Apache-2.0 */
/* On-flash record format of the store (docs/store.md has the byte layout).
 *
 * Snapshot: a body of whole cells, then one commit cell of all zero bytes:
 *   body = 'S', count, schema version u16, generation u32, key hash u32,
 *          entries (key u8, value u32 LE), 0xFF padding, CRC-32
 *   The commit cell is programmed last, after the body is read back, so a
 *   snapshot is valid only if its CRC matches and its commit cell reads
 *   zeros; a K cell that reads programmed after it then proves it solid.
 * Delta (dense, no commit cell): whole cells
 *   tag 0x80 + count - 1, entries (index u8 = snapshot index | (len - 1) << 5,
 *   value: len bytes LE, len 1..4 the fewest that hold it), 0xFF padding,
 *   CRC-32 LE in the last four bytes.
 *   A one-register commit whose value fits 16 bits is 8 bytes: one STM32G0
 *   double word. Deltas are only ever appended by the session that erased
 *   the page, each read back before the next, so only a page's last delta
 *   can be torn; its CRC decides.
 * Legacy delta ('D', count, 0, 0, 5-byte entries by key, CRC, commit cell)
 * of the store before the dense format: still read, never written. */
#ifndef KM_STORE_RECORD_H
#define KM_STORE_RECORD_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"
#include "km_store.h"

#define KM_REC_SNAPSHOT 0x53u
#define KM_REC_DELTA 0x80u        /* dense delta: tag 0x80..0x9F */
#define KM_REC_DELTA_LEGACY 0x44u /* read only */
#define KM_REC_HDR_SNAPSHOT 12u
#define KM_REC_HDR_LEGACY 4u
#define KM_REC_ENTRY 5u /* snapshot and legacy entry */
#define KM_REC_CRC 4u
#define KM_REC_MAX_CELL 8u
#define KM_REC_MAX_BYTES \
    (KM_REC_HDR_SNAPSHOT + KM_STORE_MAX_KEYS * KM_REC_ENTRY + KM_REC_CRC + 2u * KM_REC_MAX_CELL)

typedef struct {
    uint8_t type; /* KM_REC_SNAPSHOT, KM_REC_DELTA or KM_REC_DELTA_LEGACY */
    uint8_t count;
    uint16_t version;       /* snapshot only */
    uint32_t gen;           /* snapshot only */
    uint32_t hash;          /* snapshot only */
    uint32_t size;          /* bytes on flash, commit cell included */
    const uint8_t *entries; /* count entries */
} km_rec_t;

/* Bytes a snapshot of count entries takes with cells of cell bytes. */
uint32_t km_rec_snapshot_size(uint32_t count, uint32_t cell);
/* Bytes the largest delta of count entries can take (4-byte values). */
uint32_t km_rec_delta_max_size(uint32_t count, uint32_t cell);

/* Builds in buf the record of the keys in keys_mask (schema indices) with
 * their values; rec gives the type (snapshot or delta) and, for a snapshot,
 * version, gen and hash: no other field is read. Returns its size. */
uint32_t km_rec_encode(uint8_t *buf, const km_rec_t *rec, const km_store_schema_t *schema,
                       const uint32_t *values, uint32_t keys_mask, uint32_t cell);

/* Reads the record at byte offset of page, one cell at a time; true and rec filled if it is whole (version,
 * gen and hash only for a snapshot, as km_rec_t says; on false rec is not written). */
bool km_rec_read(const km_flash_t *f, uint32_t page, uint32_t offset, uint8_t *buf, km_rec_t *rec);

/* Entry i of a valid record, walked in order: *at starts at 0 and is
 * advanced. Snapshot and legacy entries give a key (*indexed false), dense
 * deltas an index into the page's snapshot (*indexed true). */
void km_rec_entry(const km_rec_t *rec, uint32_t *at, uint8_t *id, uint32_t *value, bool *indexed);

/* Reads one cell; true if it reads all ones without ECC error. */
bool km_rec_cell_erased(const km_flash_t *f, uint32_t addr);

/* Reads len bytes from addr (whole cells) a few cells per read; true if
 * every cell reads all ones without ECC error. */
bool km_rec_range_erased(const km_flash_t *f, uint32_t addr, uint32_t len);

#endif
