/* SPDX-License-Identifier: Apache-2.0 */
/* User-data store: the persisted (P) registers in a power-loss-safe journal over the hal flash contract; main
 * loop only (guarantees: docs/store.md "Notes on the code"). */
#ifndef KM_STORE_H
#define KM_STORE_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"

#define KM_STORE_MAX_KEYS 32u  /* bitmaps of keys are one u32 */
#define KM_STORE_MAX_PAGES 32u /* bitmaps of pages are one u32 */
#define KM_STORE_NO_PAGE 0xFFu

typedef struct {
    uint8_t key;  /* register address */
    uint32_t def; /* product default */
} km_store_key_t;

typedef struct {
    const km_store_key_t *keys;
    uint8_t count; /* 1..KM_STORE_MAX_KEYS, keys unique */
    /* Bump when a key's meaning or encoding changes: stored values are then
     * dropped for the defaults. Adding or removing keys needs no bump. */
    uint16_t version;
} km_store_schema_t;

typedef enum {
    KM_STORE_MOUNT_LOADED = 0,       /* stored values loaded */
    KM_STORE_MOUNT_MIGRATED,         /* key list changed: kept keys loaded, new keys default */
    KM_STORE_MOUNT_DEFAULTS_BLANK,   /* flash erased: first boot */
    KM_STORE_MOUNT_DEFAULTS_INVALID, /* no valid snapshot (garbage, QEMU 0x00 pages) */
    KM_STORE_MOUNT_DEFAULTS_SCHEMA,  /* schema version changed */
    KM_STORE_MOUNT_ERR_ARG,          /* bad geometry or schema: store unusable */
} km_store_mount_t;

typedef enum {
    KM_STORE_OK = 0,
    KM_STORE_ERR_ARG,   /* unknown or repeated key, store not mounted */
    KM_STORE_ERR_FLASH, /* program/erase error or read-back mismatch: old values stay */
} km_store_status_t;

/* All RAM of the store; contents are private. The array last: the
 * scalars stay within reach of one short load or store. */
typedef struct {
    const km_flash_t *flash;
    const km_store_schema_t *schema;
    uint32_t hash;    /* of the schema's key list */
    uint32_t gen;     /* generation of the active page's snapshot (the highest read) */
    uint32_t tail;    /* next byte offset to program in the active page, once own */
    uint32_t suspect; /* pages without a valid snapshot: erased by the first commit */
    uint32_t erased;  /* pages erased and blank-checked in this session, untouched since */
    uint8_t active;   /* page the values come from, or KM_STORE_NO_PAGE */
    uint8_t target;   /* page the session's first commit erases and writes */
    bool mounted;
    /* this session erased the active page and confirmed its snapshot:
     * deltas go after tail; before that every commit compacts */
    bool own;
    uint32_t values[KM_STORE_MAX_KEYS]; /* committed values, schema order */
} km_store_t;

/* Reads the flash and loads values (schema order) into values_out (may be
 * NULL). No flash write or erase, whatever the flash holds. */
km_store_mount_t km_store_mount(km_store_t *s, const km_flash_t *flash, const km_store_schema_t *schema,
                                uint32_t *values_out);

/* True if the mount result means product defaults are in force. */
bool km_store_mount_is_defaults(km_store_mount_t m);

/* Commits n key/value pairs, all or nothing; KM_STORE_OK once in flash and read back. */
km_store_status_t km_store_commit(km_store_t *s, const uint8_t *keys, const uint32_t *values, uint32_t n);

/* User data reset: commits the default of every key not listed in keep. */
km_store_status_t km_store_reset(km_store_t *s, const uint8_t *keep, uint32_t n_keep);

/* Idle work: early erase and compaction, one flash step per call; true if it did flash work. */
bool km_store_maintain(km_store_t *s);

/* Idle work before the session's first commit, so that commit is one
 * record with no erase: the steps that commit's compaction would take
 * (erase each page without a valid snapshot, erase the target, write the
 * mounted state as a snapshot and confirm it), at most one erase or one
 * record per call, in the same order and with the same outcome at any cut.
 * Costs one erase, so the caller decides when it is worth it (a blank or
 * outdated store: once; docs/store.md "Preparing in idle time"). Returns
 * true after a step that succeeded; false once the session owns a page,
 * or when a step failed (stop calling: the first commit then does the
 * same work, and reports the failure). */
bool km_store_prepare(km_store_t *s);

/* The committed value of key; false if key is not in the schema. */
bool km_store_get(const km_store_t *s, uint8_t key, uint32_t *value);

#endif
