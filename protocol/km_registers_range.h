/* SPDX-License-Identifier: Apache-2.0 */
/* The write range [lo, hi] of each register's fields under a product config, from km_registers.def. */
#ifndef KM_REGISTERS_RANGE_H
#define KM_REGISTERS_RANGE_H

#include <stdint.h>

#include "km_product.h"
#include "km_registers.h"

static inline void km_reg_range(km_reg_index_t reg, const km_product_t *p, int32_t *lo_out, int32_t *hi_out)
{
    (void)p;
    switch (reg) {
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi, multi, rd, wr) \
    case KM_REG_##ident:                                                           \
        *lo_out = (int32_t)(lo);                                                   \
        *hi_out = (int32_t)(hi);                                                   \
        return;
#include "km_registers.def"
#undef KM_REG
    default:
        *lo_out = 0;
        *hi_out = 0;
        return;
    }
}

#endif
