/* SPDX-License-Identifier: Apache-2.0 */
/* The register file (docs/protocol.md §4, §5): values, status bits, control's last report, latched faults;
 * owned by the dispatcher. */
#ifndef KM_REGFILE_H
#define KM_REGFILE_H

#include <stdbool.h>
#include <stdint.h>

#include "km_live.h"
#include "km_product.h"
#include "km_registers.h"
#include "km_status.h"

/* Byte fields first: every hook reaches them with one short load or store
 * (docs/footprint.md "Smaller without a change of behaviour"). */
typedef struct {
    const km_product_t *product;
    uint8_t hw_latched;           /* 0x35, latched until restart */
    uint8_t flags;                /* bits 5/6 of the command being handled */
    uint8_t unreported;           /* bits 5/6 no status answer has carried yet */
    uint32_t prng;                /* xorshift32 state for the 0x01 random byte */
    uint32_t gen;                 /* bumped on every applied register change */
    km_live_t live;               /* control's last report */
    uint32_t value[KM_REG_COUNT]; /* wire bytes packed LE */
} km_regfile_t;

/* Defaults, then the persisted values (in table order of the P registers;
 * NULL: product defaults) that pass the checks a write of them would. */
void km_regfile_init(km_regfile_t *rf, const km_product_t *product, const uint32_t *persisted, uint32_t seed);

static inline uint32_t km_regfile_get(const km_regfile_t *rf, km_reg_index_t r)
{
    return rf->value[r];
}

/* Every register change goes through here, so the change counter sees it. */
static inline void km_regfile_set(km_regfile_t *rf, km_reg_index_t r, uint32_t v)
{
    rf->value[r] = v;
    rf->gen++;
}

/* A change with its runtime mirrors (§5.4): 0x5B/0x5C/0x5D follow
 * 0x13/0x14/0x15. */
void km_regfile_apply(km_regfile_t *rf, km_reg_index_t r, uint32_t v);

/* "Limits that contradict each other": false if a runtime limit would exceed its maximum or min >= max. */
bool km_regfile_consistent(const km_regfile_t *rf, km_reg_index_t r, uint32_t v);

/* Control's report of one tick: the live registers, 0x35's latch, and 0x64
 * when control set its torque switch itself (live->torque_forced). */
void km_regfile_set_live(km_regfile_t *rf, const km_live_t *live);

/* The command being handled failed (bit 6) or was not understood (bit 5). */
static inline void km_regfile_fail(km_regfile_t *rf)
{
    rf->flags |= KM_ST_FAILED;
}

static inline void km_regfile_exception(km_regfile_t *rf)
{
    rf->flags |= KM_ST_EXCEPTION;
}

/* Bits 7 and 4..0: the live and latched state, the same in every answer. */
static inline uint8_t km_regfile_state_bits(const km_regfile_t *rf)
{
    uint8_t st = (uint8_t)(rf->live.protections & KM_ST_PROTECTION);
    if (rf->live.running) {
        st |= KM_ST_RUNNING;
    }
    if (rf->hw_latched) {
        st |= KM_ST_HW_FAULT;
    }
    return st;
}

/* What a ping (or a read of 0x01) reports: every outcome no status answer
 * has carried yet, and the current command's. */
static inline uint8_t km_regfile_status(const km_regfile_t *rf)
{
    return (uint8_t)(km_regfile_state_bits(rf) | rf->unreported | rf->flags);
}

/* What the answer to any other command reports: that command's own bits. */
static inline uint8_t km_regfile_own_status(const km_regfile_t *rf)
{
    return (uint8_t)(km_regfile_state_bits(rf) | rf->flags);
}

/* The next byte of the 0x01 random sequence (xorshift32). */
uint8_t km_regfile_random(km_regfile_t *rf);

#endif
