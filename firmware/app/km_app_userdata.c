/* SPDX-License-Identifier: Apache-2.0 */
/* Persisted registers over the store (see km_app_userdata.h). */
#include "km_app_userdata.h"

#include "km_servo.h"

_Static_assert(KM_STORE_MOUNT_LOADED == KM_USERDATA_LOADED &&
                   KM_STORE_MOUNT_MIGRATED == KM_USERDATA_MIGRATED &&
                   KM_STORE_MOUNT_DEFAULTS_BLANK == KM_USERDATA_DEFAULTS_BLANK &&
                   KM_STORE_MOUNT_DEFAULTS_INVALID == KM_USERDATA_DEFAULTS_INVALID &&
                   KM_STORE_MOUNT_DEFAULTS_SCHEMA == KM_USERDATA_DEFAULTS_SCHEMA &&
                   KM_STORE_MOUNT_ERR_ARG == KM_USERDATA_UNAVAILABLE,
               "register 0x0D reports the store's mount result as is");

static km_store_key_t s_keys[KM_USERDATA_MAX];
static km_store_schema_t s_schema;
static km_store_t s_store;

km_store_mount_t km_app_userdata_mount(const km_flash_t *flash, const km_product_t *product, uint32_t *values)
{
    uint8_t n = 0;
    for (unsigned i = 0; i < KM_REG_COUNT; i++) { /* n ends at KM_USERDATA_MAX: the persisted rows */
        if (km_reg_table[i].persisted) {
            s_keys[n].key = km_reg_table[i].addr;
            s_keys[n].def = km_reg_default((km_reg_index_t)i, product);
            n++;
        }
    }
    s_schema.keys = s_keys;
    s_schema.count = n;
    s_schema.version = KM_USERDATA_SCHEMA_VERSION;
    const km_store_mount_t m = km_store_mount(&s_store, flash, &s_schema, values);
    if (m == KM_STORE_MOUNT_ERR_ARG) {
        for (uint8_t i = 0; i < n; i++) {
            values[i] = s_keys[i].def; /* store unusable: run on defaults */
        }
    }
    return m;
}

bool km_app_userdata_commit(const uint8_t *addrs, const uint32_t *values, uint8_t n)
{
    return km_store_commit(&s_store, addrs, values, n) == KM_STORE_OK;
}

bool km_app_userdata_maintain(void)
{
    return km_store_maintain(&s_store);
}

bool km_app_userdata_prepare(void)
{
    return km_store_prepare(&s_store);
}
