/* SPDX-License-Identifier: Apache-2.0 */
/* The servo's persisted registers (docs/protocol.md §5, P column) as a store
 * schema, for the store's tests and benchmark. Product-dependent defaults
 * ("—") get plausible values; multi-value registers pack LSB first. */
#ifndef KM_STORE_TEST_SCHEMA_H
#define KM_STORE_TEST_SCHEMA_H

#include "km_store.h"

static const km_store_key_t k_test_keys[] = {
    {0x0F, 0u},        /* servo ID */
    {0x10, 1152u},     /* baud / 100 */
    {0x11, 0x02u},     /* system configuration */
    {0x12, 200u},      /* response delay */
    {0x13, 1000u},     /* max torque */
    {0x14, 1500u},     /* max current */
    {0x15, 360u},      /* max speed */
    {0x16, 0u},        /* level-1 zero offset (factory) */
    {0x17, 0u},        /* level-2 zero offset */
    {0x19, 0xFA9Cu},   /* min angle -1380 as u16 */
    {0x1A, 1380u},     /* max angle */
    {0x32, 0x0Fu},     /* protection enable */
    {0x33, 0x00u},     /* release mode */
    {0x34, 0x54u},     /* state while protecting */
    {0x3C, 0x5A8Cu},   /* voltage high 140, low 90 */
    {0x3D, 0x053Cu},   /* temperature 60, hysteresis 5 */
    {0x3E, 0x1405DCu}, /* current 1500 mA, 20 */
    {0x3F, 0x140258u}, /* stall 600, 20 */
};

static const km_store_schema_t k_test_schema = {
    .keys = k_test_keys,
    .count = (uint8_t)(sizeof k_test_keys / sizeof k_test_keys[0]),
    .version = 1u,
};

#endif
