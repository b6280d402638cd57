/* SPDX-License-Identifier: Apache-2.0 */
/* The register table generated from km_registers.def, and the checks every
 * write passes before anything changes (docs/protocol.md §4: out of range or
 * wrong length = nothing changes, status bit 6). */
#include "km_registers.h"
#include "km_registers_range.h"

const km_reg_t km_reg_table[KM_REG_COUNT] = {
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi, multi, rd, wr) \
    {addr, layout, access, persisted, (uint8_t)(multi)},
#include "km_registers.def"
#undef KM_REG
};

#if KM_PROTOCOL_COMPACT
int km_reg_find(uint8_t addr)
{
    uint32_t lo = 0u;           /* every row below lo has a smaller address */
    uint32_t hi = KM_REG_COUNT; /* every row from hi on has a larger one */
    while (lo < hi) {
        const uint32_t mid = (lo + hi) / 2u;
        const uint8_t at = km_reg_table[mid].addr;
        if (at == addr) {
            return (int)mid;
        }
        if (at < addr) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return -1;
}
#else
const uint8_t km_reg_by_addr[KM_REG_ADDR_SPAN] = {
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi, multi, rd, wr) \
    [addr] = KM_REG_##ident + 1,
#include "km_registers.def"
#undef KM_REG
};
#endif

#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi, multi, rd, wr) \
    _Static_assert((addr) < KM_REG_ADDR_SPAN, "register address beyond km_reg_by_addr");
#include "km_registers.def"
#undef KM_REG

static uint32_t prv_default_raw(km_reg_index_t reg, const km_product_t *p)
{
    (void)p;
    switch (reg) {
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi, multi, rd, wr) \
    case KM_REG_##ident:                                                           \
        return (uint32_t)(def);
#include "km_registers.def"
#undef KM_REG
    default:
        return 0;
    }
}

uint32_t km_reg_default(km_reg_index_t reg, const km_product_t *p)
{
    /* Packed as the wire bytes, as km_reg_validate() packs a written value. */
    const uint32_t v = prv_default_raw(reg, p);
    const uint8_t size = km_reg_fixed_size((km_layout_t)km_reg_table[reg].layout);
    return size > 0u && size < 4u ? v & ((1u << (8u * size)) - 1u) : v;
}

uint8_t km_reg_fixed_size(km_layout_t layout)
{
    return km_reg_fixed_size_const(layout);
}

uint8_t km_put_le(uint8_t *out, uint32_t value, uint8_t size)
{
    for (uint8_t i = 0; i < size; i++) {
        out[i] = (uint8_t)(value >> (8u * i));
    }
    return size;
}

uint32_t km_get_le(const uint8_t *in, uint8_t n)
{
    uint32_t v = 0;
    for (uint8_t i = 0; i < n; i++) {
        v |= (uint32_t)in[i] << (8u * i);
    }
    return v;
}

static bool prv_in(int32_t v, int32_t lo, int32_t hi)
{
    return v >= lo && v <= hi;
}

/* Second fields and cross-field rules of the multi-field registers. */
static bool prv_cross_check(km_reg_index_t reg, uint32_t packed)
{
    switch (reg) {
    case KM_REG_PROT_STATE:
        /* §5.2 0x34: temperature [5:4] and voltage [1:0] allow only 00/01. */
        return (packed & 0x22u) == 0;
    case KM_REG_VOLTAGE_LIMITS:
        /* high V must exceed low V, or the supply is always "abnormal". */
        return (packed & 0xFFu) > ((packed >> 8) & 0xFFu);
    case KM_REG_TEMP_LIMITS:
        /* release hysteresis below the trip temperature */
        return ((packed >> 8) & 0xFFu) < (packed & 0xFFu);
    case KM_REG_CURRENT_LIMIT:
    case KM_REG_STALL_LIMIT:
        /* detection time in 100 ms units: 0 would trip on one sample */
        return ((packed >> 16) & 0xFFu) >= 1u;
    default:
        return true;
    }
}

/* Bytes a write of `layout` takes (0: checked by its hook). */
static uint8_t prv_write_size(km_layout_t layout, uint8_t len)
{
    switch (layout) {
    case KM_L_U8:
    case KM_L_BITS8:
    case KM_L_I8:
    case KM_L_U16:
    case KM_L_I16:
    case KM_L_U8U8:
    case KM_L_U16U8:
        return km_reg_fixed_size_const(layout);
    case KM_L_MOVE:
        return len == 4u ? 4u : 2u;
    default:
        return 0u;
    }
}

/* The first field of a write's bytes, as the number it means. */
static int32_t prv_first_field(km_layout_t layout, const uint8_t *data)
{
    switch (layout) {
    case KM_L_I8:
        return (int8_t)data[0];
    case KM_L_I16:
    case KM_L_MOVE:
        return (int16_t)km_get_le(data, 2);
    case KM_L_U16:
    case KM_L_U16U8:
        return (int32_t)km_get_le(data, 2);
    default: /* KM_L_U8, KM_L_U8U8 */
        return data[0];
    }
}

bool km_reg_validate(km_reg_index_t reg, const km_product_t *p, const uint8_t *data, uint8_t len,
                     uint32_t *packed)
{
    const km_layout_t layout = (km_layout_t)km_reg_table[reg].layout;
    int32_t lo, hi;
    km_reg_range(reg, p, &lo, &hi);
    const uint8_t size = prv_write_size(layout, len);
    if (size == 0u || len != size) {
        return false;
    }
    if (layout == KM_L_BITS8) {
        /* "Reserved bits": the vendor's tables mark them "retain", and
         * masters write whole bytes: accepted, kept at 0. */
        *packed = (uint32_t)data[0] & (uint32_t)hi;
        return true;
    }
    if ((layout == KM_L_U8U8 && !prv_in(data[1], lo, hi)) || !prv_in(prv_first_field(layout, data), lo, hi)) {
        return false;
    }
    *packed = km_get_le(data, len);
    return prv_cross_check(reg, *packed);
}
