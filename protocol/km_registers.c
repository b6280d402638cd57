/* The register table generated from km_registers.def, and the checks every
 * write passes before anything changes (PROTOCOL.md §4: out of range or
 * wrong length = nothing changes, status bit 6). */
#include "km_registers.h"
#include "km_registers_range.h"

const km_reg_t km_reg_table[KM_REG_COUNT] = {
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi) \
    {addr, access, persisted, layout, #ident},
#include "km_registers.def"
#undef KM_REG
};

int km_reg_find(uint8_t addr)
{
    /* The table is sorted by address: a binary search keeps the cost at
     * six probes for 47 registers. */
    int lo = 0;
    int hi = (int)KM_REG_COUNT - 1;
    while (lo <= hi) {
        const int mid = (lo + hi) / 2;
        if (km_reg_table[mid].addr == addr) {
            return mid;
        }
        if (km_reg_table[mid].addr < addr) {
            lo = mid + 1;
        } else {
            hi = mid - 1;
        }
    }
    return -1;
}

static uint32_t prv_default_raw(km_reg_index_t reg, const km_product_t *p)
{
    (void)p;
    switch (reg) {
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi) \
    case KM_REG_##ident:                                            \
        return (uint32_t)(def);
#include "km_registers.def"
#undef KM_REG
    default:
        return 0;
    }
}

uint32_t km_reg_default(km_reg_index_t reg, const km_product_t *p)
{
    /* Packed as the wire bytes: a negative i16 default (an angle limit, a
     * zero offset) is its two bytes, not a sign-extended u32, the same as
     * km_reg_validate() packs a written value. */
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

bool km_reg_validate(km_reg_index_t reg, const km_product_t *p, const uint8_t *data,
                     uint8_t len, uint32_t *packed)
{
    const km_layout_t layout = (km_layout_t)km_reg_table[reg].layout;
    int32_t lo, hi;
    km_reg_range(reg, p, &lo, &hi);
    int32_t first;
    switch (layout) {
    case KM_L_U8:
        if (len != 1) return false;
        first = data[0];
        break;
    case KM_L_BITS8:
        /* "Reserved bits": the vendor's tables mark them "retain", and
         * masters write whole bytes: accepted, kept at 0. */
        if (len != 1) return false;
        *packed = (uint32_t)data[0] & (uint32_t)hi;
        return true;
    case KM_L_I8:
        if (len != 1) return false;
        first = (int8_t)data[0];
        break;
    case KM_L_U16:
    case KM_L_U16U8:
        if (len != km_reg_fixed_size(layout)) return false;
        first = (int32_t)km_get_le(data, 2);
        break;
    case KM_L_I16:
        if (len != 2) return false;
        first = (int16_t)km_get_le(data, 2);
        break;
    case KM_L_U8U8:
        if (len != 2) return false;
        if (!prv_in(data[1], lo, hi)) return false;
        first = data[0];
        break;
    case KM_L_MOVE:
        if (len != 2 && len != 4) return false;
        first = (int16_t)km_get_le(data, 2);
        break;
    default:
        /* Computed or action layouts are checked by the dispatcher. */
        return false;
    }
    if (!prv_in(first, lo, hi)) {
        return false;
    }
    *packed = km_get_le(data, len);
    return prv_cross_check(reg, *packed);
}
