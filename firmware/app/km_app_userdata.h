/* SPDX-License-Identifier: Apache-2.0 */
/* The persisted registers (P in docs/protocol.md §5) over the user-data store:
 * the schema is built from the register table, defaults from the product. */
#ifndef KM_APP_USERDATA_H
#define KM_APP_USERDATA_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"
#include "km_product.h"
#include "km_store.h"

#include "km_registers.h"

#define KM_USERDATA_MAX KM_REG_PERSISTED_COUNT
/* Bump when a persisted register's meaning or encoding changes (stored
 * values then give way to the defaults; the bootloader mounts with it). */
#define KM_USERDATA_SCHEMA_VERSION 1u
_Static_assert(KM_USERDATA_MAX <= KM_STORE_MAX_KEYS, "the store holds every persisted register");

/* Mounts the store (no flash operation) and fills `values` in table order. */
km_store_mount_t km_app_userdata_mount(const km_flash_t *flash, const km_product_t *product,
                                       uint32_t *values);

/* The dispatcher's commit: all-or-nothing, true once durable. */
bool km_app_userdata_commit(const uint8_t *addrs, const uint32_t *values, uint8_t n);

/* Idle-time compaction; true if it did flash work. */
bool km_app_userdata_maintain(void);

/* Idle-time preparation of the session's first commit (km_store_prepare):
 * true after a step that succeeded, false when done or after a failure. */
bool km_app_userdata_prepare(void);

#endif
