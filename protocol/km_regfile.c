/* SPDX-License-Identifier: Apache-2.0 */
/* The register file (see km_regfile.h): start-up values, the runtime
 * mirrors, the cross-register rules and control's report. */
#include "km_regfile.h"

#include <string.h>

/* "Limits that contradict each other": a minimum angle limit at or above
 * the maximum would leave no target reachable. 0 = no limit (§5.1). */
static bool prv_angle_limits_ok(int16_t lo, int16_t hi)
{
    return lo == 0 || hi == 0 || lo < hi;
}

/* The maxima 0x13..0x15 and the limits in force 0x5B..0x5D pair up row by row: a limit is its
 * maximum's index + PRV_LIMIT_OF_MAX. */
#define PRV_LIMIT_OF_MAX (KM_REG_TORQUE_LIMIT - KM_REG_MAX_TORQUE)
_Static_assert(KM_REG_MAX_CURRENT == KM_REG_MAX_TORQUE + 1 && KM_REG_MAX_SPEED == KM_REG_MAX_TORQUE + 2 &&
                   KM_REG_CURRENT_LIMIT_NOW == KM_REG_MAX_CURRENT + PRV_LIMIT_OF_MAX &&
                   KM_REG_SPEED_LIMIT == KM_REG_MAX_SPEED + PRV_LIMIT_OF_MAX,
               "km_registers.def: 0x13..0x15 and 0x5B..0x5D must stay in the same order");

/* A stored value passes the checks a write of it would, else the default. */
static bool prv_persisted_ok(km_reg_index_t r, const km_product_t *p, uint32_t v)
{
    uint8_t b[4];
    uint32_t packed;
    const uint8_t n = km_reg_fixed_size((km_layout_t)km_reg_table[r].layout);
    if (n == 0u || n > 3u) {
        return false;
    }
    km_put_le(b, v, n);
    return km_reg_validate(r, p, b, n, &packed) && packed == v;
}

void km_regfile_init(km_regfile_t *rf, const km_product_t *product, const uint32_t *persisted, uint32_t seed)
{
    memset(rf, 0, sizeof *rf);
    rf->product = product;
    unsigned k = 0;
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        uint32_t v = km_reg_default((km_reg_index_t)i, product);
        if (km_reg_table[i].persisted && persisted &&
            prv_persisted_ok((km_reg_index_t)i, product, persisted[k])) {
            v = persisted[k];
        }
        k += km_reg_table[i].persisted;
        km_regfile_apply(rf, (km_reg_index_t)i, v);
    }
    /* The values from one base register (docs/footprint.md "Register values from one base"). */
    uint32_t *value = rf->value;
    __asm__("" : "+r"(value));
    /* §5.4: 0x5B..0x5D start equal to the stored 0x13..0x15: mirror again after the defaults. */
    for (unsigned r = KM_REG_MAX_TORQUE; r <= KM_REG_MAX_SPEED; r++) {
        value[r + PRV_LIMIT_OF_MAX] = value[r];
        rf->gen++;
    }
    /* "Limits that contradict each other" apply to stored values too. */
    if (!prv_angle_limits_ok((int16_t)value[KM_REG_ANGLE_MIN], (int16_t)value[KM_REG_ANGLE_MAX])) {
        value[KM_REG_ANGLE_MIN] = km_reg_default(KM_REG_ANGLE_MIN, product);
        value[KM_REG_ANGLE_MAX] = km_reg_default(KM_REG_ANGLE_MAX, product);
    }
    rf->prng = seed ? seed : 0x2545F491u;
}

void km_regfile_apply(km_regfile_t *rf, km_reg_index_t r, uint32_t v)
{
    km_regfile_set(rf, r, v);
    if (r >= KM_REG_MAX_TORQUE && r <= KM_REG_MAX_SPEED) {
        rf->value[r + PRV_LIMIT_OF_MAX] = v;
    }
}

bool km_regfile_consistent(const km_regfile_t *rf, km_reg_index_t r, uint32_t v)
{
    switch (r) {
    case KM_REG_TORQUE_LIMIT:
    case KM_REG_CURRENT_LIMIT_NOW:
    case KM_REG_SPEED_LIMIT:
        return v <= rf->value[r - PRV_LIMIT_OF_MAX];
    case KM_REG_ANGLE_MIN:
        return prv_angle_limits_ok((int16_t)v, (int16_t)rf->value[KM_REG_ANGLE_MAX]);
    case KM_REG_ANGLE_MAX:
        return prv_angle_limits_ok((int16_t)rf->value[KM_REG_ANGLE_MIN], (int16_t)v);
    default:
        return true;
    }
}

void km_regfile_set_live(km_regfile_t *rf, const km_live_t *live)
{
    rf->live = *live;
    rf->hw_latched |= live->hw_faults; /* §5.2 0x35: latched until restart */
    if (live->torque_forced && rf->value[KM_REG_TORQUE_SWITCH] != live->torque_switch) {
        km_regfile_set(rf, KM_REG_TORQUE_SWITCH, live->torque_switch); /* §5.4 0x64 = 5: set by the servo */
    }
}

uint8_t km_regfile_random(km_regfile_t *rf)
{
    uint32_t x = rf->prng; /* xorshift32: never 0 from a non-zero seed */
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    rf->prng = x;
    return (uint8_t)x;
}
