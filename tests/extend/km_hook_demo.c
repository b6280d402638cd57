/* SPDX-License-Identifier: Apache-2.0 */
/* The one hook of the register tests/extend adds (rows.def): a write of an
 * i16 adds it to the value kept, within the register's range; a sum
 * outside it is a bad value (bit 6) and changes nothing. */
#include "km_hooks.h"

#include "km_servo.h"

/* A write adds its value to the value kept. */
void km_wr_demo_accumulate(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    uint32_t v;
    if (!km_reg_validate(r, s->reg.product, d, len, &v)) {
        km_regfile_fail(&s->reg);
        return;
    }
    const int32_t sum = (int16_t)km_regfile_get(&s->reg, r) + (int16_t)v;
    if (sum < -1000 || sum > 1000) {
        km_regfile_fail(&s->reg);
        return;
    }
    km_regfile_set(&s->reg, r, (uint16_t)(int16_t)sum);
}
