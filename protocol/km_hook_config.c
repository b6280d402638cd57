/* SPDX-License-Identifier: Apache-2.0 */
/* Write hooks of the configuration actions: restart (0x02), user-data
 * reset (0x03), the zero-offset increment (0x18), zeroing by a 0x46 write,
 * the protection clear (0x36), and the control mode (0x5A). */
#include "km_hooks.h"

#include <string.h>

#include "km_servo.h"

static const uint8_t s_restart_magic[4] = {0xE1, 0xE2, 0xE3, 0xE4};

static bool prv_is_encoder(const km_servo_t *s)
{
    return km_product_variant(s->reg.product) == KM_VARIANT_ENCODER;
}

/* 0x02: exactly E1 E2 E3 E4 restarts at once ("Restart": nothing after
 * this frame may run, no answer); anything else is a bad value. */
void km_wr_restart(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    (void)r;
    if (len != 4 || memcmp(d, s_restart_magic, 4) != 0) {
        km_regfile_fail(&s->reg);
        return;
    }
    s->restarting = true;
    if (s->ops && s->ops->restart) {
        s->ops->restart(s->ops->ctx);
    }
}

/* What a level-1 reset keeps: ID, baud and the zero offset, one bit per register index. */
#define PRV_KEPT_AT_LEVEL_1 ((1u << KM_REG_ID) | (1u << KM_REG_BAUD) | (1u << KM_REG_ZERO_OFFSET2))
_Static_assert(KM_REG_ID < 32 && KM_REG_BAUD < 32 && KM_REG_ZERO_OFFSET2 < 32,
               "kept registers beyond the mask");

/* The registers a user-data reset writes back and their defaults, in
 * table order; returns how many ("User-data reset"). */
static uint8_t prv_reset_list(const km_product_t *p, uint8_t level, uint8_t *regs, uint8_t *addrs,
                              uint32_t *values)
{
    const uint32_t kept = level == 1u ? PRV_KEPT_AT_LEVEL_1 : 0u;
    uint8_t n = 0;
    for (uint8_t i = 0; i < (uint8_t)KM_REG_COUNT; i++) {
        const km_reg_t *t = &km_reg_table[i];
        if (t->persisted && (t->access & KM_W) && !(i < 32u && ((kept >> i) & 1u))) {
            regs[n] = i;
            addrs[n] = t->addr;
            values[n] = km_reg_default((km_reg_index_t)i, p);
            n++;
        }
    }
    return n;
}

/* 0x03: 1 resets the user data but ID, baud and zero offsets, 2 all of
 * it; committed all or nothing, then applied. */
void km_wr_userdata_reset(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    uint32_t level;
    if (!km_reg_validate(r, s->reg.product, d, len, &level)) {
        km_regfile_fail(&s->reg);
        return;
    }
    /* The register indexes are kept beside the addresses, so applying the
     * committed values needs no look-up by address. */
    uint8_t regs[KM_REG_PERSISTED_COUNT];
    uint8_t addrs[KM_REG_PERSISTED_COUNT];
    uint32_t values[KM_REG_PERSISTED_COUNT];
    const uint8_t n = prv_reset_list(s->reg.product, (uint8_t)level, regs, addrs, values);
    if (!km_hook_commit(s, addrs, values, n)) {
        km_regfile_fail(&s->reg);
        return;
    }
    for (uint8_t j = 0; j < n; j++) {
        km_regfile_apply(&s->reg, (km_reg_index_t)regs[j], values[j]);
    }
}

/* "Zeroing": 0x46 and 0x18 = 0 refused (bit 6) while a hardware fault is latched. */
static void prv_zero_position(km_servo_t *s)
{
    const km_request_t req = {.kind = KM_REQ_ZERO_POSITION};
    if (s->reg.hw_latched || !km_hook_request(s, &req)) {
        km_regfile_fail(&s->reg);
    }
}

/* 0x18: added to 0x17 (committed) within its bound; 0 zeroes an encoder. */
void km_wr_zero_increment(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    uint32_t v;
    if (!km_reg_validate(r, s->reg.product, d, len, &v)) {
        km_regfile_fail(&s->reg);
        return;
    }
    const int8_t inc = (int8_t)v;
    if (inc == 0 && prv_is_encoder(s)) { /* §5.1 0x18: 0 zeroes an encoder */
        prv_zero_position(s);
        return;
    }
    const int32_t next = (int16_t)km_regfile_get(&s->reg, KM_REG_ZERO_OFFSET2) + inc;
    const int32_t bound = s->reg.product->zero_offset2_max;
    if (next < -bound || next > bound) {
        km_regfile_fail(&s->reg);
        return;
    }
    km_hook_commit_one(s, KM_REG_ZERO_OFFSET2, (uint32_t)(uint16_t)(int16_t)next);
}

/* §5.3 0x46: any value (i16 or i32) zeroes it, on motor (encoder) products. */
void km_wr_zero_position(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    (void)r;
    (void)d;
    if ((len != 2 && len != 4) || !prv_is_encoder(s)) {
        km_regfile_fail(&s->reg);
        return;
    }
    prv_zero_position(s);
}

/* §5.2 0x36: write 1 to a bit to clear that protection; a protection
 * whose cause still holds stays (control refuses: bit 6). Nothing stored:
 * 0x36 reads the protections acting. */
void km_wr_prot_clear(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    uint32_t v;
    if (!km_reg_validate(r, s->reg.product, d, len, &v)) {
        km_regfile_fail(&s->reg);
        return;
    }
    const km_request_t req = {.kind = KM_REQ_PROTECTION_CLEAR, .u.clear = (uint8_t)v};
    if (!km_hook_request(s, &req)) {
        km_regfile_fail(&s->reg);
    }
}

/* §5.4 0x5A: 0 auto, 1 servo only, 2 motor only; switching to motor only
 * is refused (bit 6) while the servo runs with its torque on (0x64 = 2): a
 * move would be cut off mid-way. Otherwise stored as written. */
void km_wr_control_mode(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    uint32_t v;
    if (!km_reg_validate(r, s->reg.product, d, len, &v) ||
        (v == KM_MODE_MOTOR_ONLY && s->reg.live.running &&
         km_regfile_get(&s->reg, KM_REG_TORQUE_SWITCH) == KM_TORQUE_ON)) {
        km_regfile_fail(&s->reg);
        return;
    }
    km_regfile_set(&s->reg, r, v);
}
