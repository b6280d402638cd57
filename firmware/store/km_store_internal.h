/* SPDX-License-Identifier: Apache-2.0 */
/* Helpers shared by the store's source files; not part of the API. */
#ifndef KM_STORE_INTERNAL_H
#define KM_STORE_INTERNAL_H

#include <stdint.h>

#include "km_store.h"

/* Schema index of key, or -1. */
int32_t km_store_index(const km_store_schema_t *schema, uint8_t key);
/* Bitmap with one bit per schema key. */
uint32_t km_store_all_keys(const km_store_schema_t *schema);

#endif
