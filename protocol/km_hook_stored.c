/* SPDX-License-Identifier: Apache-2.0 */
/* The hooks of plain registers (`stored`, `none`), the hook tables the
 * dispatcher calls through, and what every hook may use to reach the rest
 * of the firmware (km_hooks.h). */
#include "km_hooks.h"

#include "km_servo.h"

/* Each hook's index in the lists below. */
enum {
#define KM_HOOK_INDEX(name) KM_RDH_##name,
    KM_RD_HOOKS(KM_HOOK_INDEX)
#undef KM_HOOK_INDEX
        KM_RDH_COUNT
};
enum {
#define KM_HOOK_INDEX(name) KM_WRH_##name,
    KM_WR_HOOKS(KM_HOOK_INDEX)
#undef KM_HOOK_INDEX
        KM_WRH_COUNT
};
_Static_assert(KM_RDH_COUNT <= (1u << KM_RD_HOOK_BITS) && KM_WRH_COUNT <= (1u << KM_WR_HOOK_BITS),
               "a hook index does not fit its bit-field");

const km_read_hook_t km_rd_hooks[KM_RDH_COUNT] = {
#define KM_HOOK_ENTRY(name) km_rd_##name,
    KM_RD_HOOKS(KM_HOOK_ENTRY)
#undef KM_HOOK_ENTRY
};

const km_write_hook_t km_wr_hooks[KM_WRH_COUNT] = {
#define KM_HOOK_ENTRY(name) km_wr_##name,
    KM_WR_HOOKS(KM_HOOK_ENTRY)
#undef KM_HOOK_ENTRY
};

const km_reg_hooks_t km_reg_hooks[KM_REG_COUNT] = {
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi, multi, rd, wr) {KM_WRH_##wr, KM_RDH_##rd},
#include "km_registers.def"
#undef KM_REG
};

bool km_hook_request(km_servo_t *s, const km_request_t *req)
{
    if (s->ops && s->ops->request) {
        return s->ops->request(s->ops->ctx, req);
    }
    return true;
}

bool km_hook_commit(km_servo_t *s, const uint8_t *addrs, const uint32_t *values, uint8_t n)
{
    return s->ops && s->ops->commit && s->ops->commit(s->ops->ctx, addrs, values, n);
}

void km_hook_commit_one(km_servo_t *s, km_reg_index_t r, uint32_t v)
{
    const uint8_t addr = km_reg_table[r].addr;
    if (!km_hook_commit(s, &addr, &v, 1)) {
        km_regfile_fail(&s->reg); /* the store failed: the old value stays in force */
        return;
    }
    km_regfile_apply(&s->reg, r, v);
}

/* The value as kept, its fixed number of wire bytes. */
uint8_t km_rd_stored(km_servo_t *s, km_reg_index_t r, uint8_t *out)
{
    return km_put_le(out, km_regfile_get(&s->reg, r), km_reg_fixed_size((km_layout_t)km_reg_table[r].layout));
}

/* Checked (length, range, cross-field rules, "Limits that contradict each
 * other"), then committed before it applies if persisted (ID and baud
 * too), else applied. Anything wrong: bit 6, nothing changes (§4). */
void km_wr_stored(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    uint32_t v;
    if (!km_reg_validate(r, s->reg.product, d, len, &v) || !km_regfile_consistent(&s->reg, r, v)) {
        km_regfile_fail(&s->reg);
    } else if (km_reg_table[r].persisted) {
        km_hook_commit_one(s, r, v);
    } else {
        km_regfile_set(&s->reg, r, v);
    }
}

/* A write-only register is never read: the dispatcher answers bit 5 for
 * it first (km_dispatch_readable). Nothing. */
uint8_t km_rd_none(km_servo_t *s, km_reg_index_t r, uint8_t *out)
{
    (void)s;
    (void)r;
    (void)out;
    return 0u;
}

/* A read-only register (0x16 included): bit 5, nothing changes. */
void km_wr_none(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    (void)r;
    (void)d;
    (void)len;
    km_regfile_exception(&s->reg);
}
