/* SPDX-License-Identifier: Apache-2.0 */
/* Register hooks: what a read or a write of one register does (km_registers.def names them;
 * docs/architecture.md "Register hooks"). */
#ifndef KM_HOOKS_H
#define KM_HOOKS_H

#include <stdbool.h>
#include <stdint.h>

#include "km_registers.h"
#include "km_request.h"

/* Generated from the .def (tools/gen/reg-hooks); after km_registers.h, as the .def. */
#include "km_reg_hooks.h"

struct km_servo;

typedef uint8_t (*km_read_hook_t)(struct km_servo *s, km_reg_index_t r, uint8_t *out);
typedef void (*km_write_hook_t)(struct km_servo *s, km_reg_index_t r, const uint8_t *d, uint8_t len);

/* Every hook the .def names, declared (a hook used by several registers
 * is declared once per register: compatible redeclarations). */
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi, multi, rd, wr) \
    uint8_t km_rd_##rd(struct km_servo *s, km_reg_index_t r, uint8_t *out);        \
    void km_wr_##wr(struct km_servo *s, km_reg_index_t r, const uint8_t *d, uint8_t len);
#include "km_registers.def"
#undef KM_REG

/* Each distinct hook once (KM_RD_HOOKS, KM_WR_HOOKS: generated from the
 * .def by tools/gen/reg-hooks), and per register the index of its two
 * (km_hook_stored.c; docs/architecture.md "Register hooks"). */
extern const km_read_hook_t km_rd_hooks[];
extern const km_write_hook_t km_wr_hooks[];

/* The read index in the upper bits: one shift to extract on the answer paths. */
typedef struct {
    uint8_t wr : KM_WR_HOOK_BITS; /* index into km_wr_hooks */
    uint8_t rd : KM_RD_HOOK_BITS; /* index into km_rd_hooks */
} km_reg_hooks_t;

extern const km_reg_hooks_t km_reg_hooks[KM_REG_COUNT];

/* The read hook of the register at table index r (km_reg_find()'s int). */
static inline km_read_hook_t km_reg_read(int r)
{
    return km_rd_hooks[km_reg_hooks[r].rd];
}

/* The write hook of the register at table index r (km_reg_find()'s int). */
static inline km_write_hook_t km_reg_write(int r)
{
    return km_wr_hooks[km_reg_hooks[r].wr];
}

/* A typed request to control; true when accepted (no control attached:
 * accepted). */
bool km_hook_request(struct km_servo *s, const km_request_t *req);

/* Persisted registers all-or-nothing through the store; true once durable. */
bool km_hook_commit(struct km_servo *s, const uint8_t *addrs, const uint32_t *values, uint8_t n);

/* One persisted register committed, then applied; bit 6 if the store
 * failed (the old value stays in force). */
void km_hook_commit_one(struct km_servo *s, km_reg_index_t r, uint32_t v);

#endif
