/* SPDX-License-Identifier: Apache-2.0 */
/* NOR flash simulator: controller rules, counters and power-cut outcomes.
 * See km_nor_sim.h for the model. */
#include "km_nor_sim.h"

#include <string.h>

enum {
    CELL_ERASED = 0,
    CELL_PROGRAMMED, /* fully programmed (even if its value is all ones) */
    CELL_TORN_ONES,  /* program began, no bit moved: passes the erased check */
    CELL_TORN_MIXED,
    CELL_UNSTABLE, /* data = a mix, alt = the target: reads one or the other */
    CELL_ECC,
    CELL_WEAK, /* data = high side, alt = low side: reads either or between */
};

static uint32_t prv_rand(km_nor_sim_t *sim)
{
    /* xorshift32: deterministic per seed, so every failure replays. */
    uint32_t x = sim->rng;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    sim->rng = x;
    return x;
}

static uint32_t prv_total(const km_nor_sim_t *sim)
{
    return sim->cfg.page_size * sim->cfg.page_count;
}

static bool prv_is_all_ones(const uint8_t *p, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++) {
        if (p[i] != 0xFFu) {
            return false;
        }
    }
    return true;
}

/* A half-programmed cell: some of the bits the target clears are cleared.
 * Made to differ from the target and, when the target clears at least two
 * bits, from all ones, so the tear is visible to a reader. */
static void prv_mix(km_nor_sim_t *sim, uint8_t *out, const uint8_t *target, uint32_t n)
{
    uint32_t zeros = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint8_t clear = (uint8_t)~target[i];
        out[i] = (uint8_t)(0xFFu & ~(clear & (uint8_t)prv_rand(sim)));
        for (uint8_t b = clear; b != 0u; b = (uint8_t)(b & (b - 1u))) {
            zeros++;
        }
    }
    if (zeros < 2u) {
        memset(out, 0xFF, n);
        return;
    }
    if (memcmp(out, target, n) == 0) {
        /* Leave the first bit to clear still set. */
        for (uint32_t i = 0; i < n; i++) {
            uint8_t clear = (uint8_t)~target[i];
            if (clear != 0u) {
                out[i] = (uint8_t)(out[i] | (clear & (uint8_t)(-(int)clear)));
                break;
            }
        }
    }
    if (prv_is_all_ones(out, n)) {
        /* Clear the first bit to clear, which differs from the target since
         * the target clears at least two bits. */
        for (uint32_t i = 0; i < n; i++) {
            uint8_t clear = (uint8_t)~target[i];
            if (clear != 0u) {
                out[i] = (uint8_t)(out[i] & ~(clear & (uint8_t)(-(int)clear)));
                break;
            }
        }
    }
}

static void prv_tear_cell(km_nor_sim_t *sim, uint32_t cell, const uint8_t *target, km_nor_prog_outcome_t o)
{
    const uint32_t c = sim->cfg.prog_size;
    uint8_t *d = &sim->data[cell * c];
    switch (o) {
    case KM_NOR_PROG_NOT_DONE:
        break;
    case KM_NOR_PROG_DONE:
        memcpy(d, target, c);
        sim->state[cell] = CELL_PROGRAMMED;
        break;
    case KM_NOR_PROG_TORN_ONES:
        sim->state[cell] = CELL_TORN_ONES;
        break;
    case KM_NOR_PROG_TORN_WEAK:
        /* data stays all ones (the erased side), alt is the target. */
        memcpy(&sim->alt[cell * c], target, c);
        sim->state[cell] = CELL_WEAK;
        break;
    case KM_NOR_PROG_TORN_MIXED:
    case KM_NOR_PROG_TORN_UNSTABLE:
    case KM_NOR_PROG_TORN_ECC:
    default:
        prv_mix(sim, d, target, c);
        memcpy(&sim->alt[cell * c], target, c);
        if (prv_is_all_ones(d, c) && o != KM_NOR_PROG_TORN_ECC) {
            sim->state[cell] = CELL_TORN_ONES;
        } else if (o == KM_NOR_PROG_TORN_MIXED) {
            sim->state[cell] = CELL_TORN_MIXED;
        } else if (o == KM_NOR_PROG_TORN_UNSTABLE) {
            sim->state[cell] = CELL_UNSTABLE;
        } else {
            sim->state[cell] = CELL_ECC;
        }
        break;
    }
}

/* One cell as a read sees it now; true unless it reports an ECC error.
 * Weak cells draw their value here, so two reads may differ. */
static bool prv_read_cell(km_nor_sim_t *sim, uint32_t cell, uint8_t *out)
{
    const uint32_t c = sim->cfg.prog_size;
    const uint8_t *hi = &sim->data[cell * c];
    const uint8_t *lo = &sim->alt[cell * c];
    const uint8_t st = sim->state[cell];
    if (st == CELL_UNSTABLE || st == CELL_WEAK) {
        uint32_t pick = 1u; /* 0 high side, 1 low side, 2 a mix */
        if (sim->weak_reads == KM_NOR_WEAK_HIGH) {
            pick = 0u;
        } else if (sim->weak_reads == KM_NOR_WEAK_RANDOM) {
            pick = (prv_rand(sim) >> 7) & 3u;
            /* An unstable cell reads the target or its mix, nothing else. */
            pick = (st == CELL_UNSTABLE) ? (pick & 1u) : ((pick == 3u) ? 2u : pick);
        }
        for (uint32_t i = 0; i < c; i++) {
            if (pick == 2u) {
                /* Bits between the sides read 0 or 1 independently. */
                const uint8_t between = (uint8_t)(hi[i] & ~lo[i]);
                out[i] = (uint8_t)(hi[i] & ~(between & (uint8_t)prv_rand(sim)));
            } else {
                out[i] = (pick == 0u) ? hi[i] : lo[i];
            }
        }
        return true;
    }
    memcpy(out, hi, c);
    return st != CELL_ECC;
}

/* The controller's "is it erased" check before a program. */
static bool prv_check_erased(km_nor_sim_t *sim, uint32_t cell)
{
    const uint8_t st = sim->state[cell];
    if (sim->rules.content_check) {
        uint8_t now[8];
        return prv_read_cell(sim, cell, now) && prv_is_all_ones(now, sim->cfg.prog_size);
    }
    return st == CELL_ERASED || (st == CELL_TORN_ONES && !sim->rules.ecc_dword);
}

/* A program the check let through onto a cell that was not cleanly erased:
 * bits only clear, so both sides of the cell are ANDed with the new value;
 * on an ECC flash the stored ECC no longer matches anything. */
static void prv_program_over(km_nor_sim_t *sim, uint32_t cell, const uint8_t *src)
{
    const uint32_t c = sim->cfg.prog_size;
    uint8_t *hi = &sim->data[cell * c];
    uint8_t *lo = &sim->alt[cell * c];
    const uint8_t st = sim->state[cell];
    const bool two_sided = (st == CELL_UNSTABLE || st == CELL_WEAK);
    for (uint32_t i = 0; i < c; i++) {
        lo[i] = (uint8_t)((two_sided ? lo[i] : hi[i]) & src[i]);
        hi[i] = (uint8_t)(hi[i] & src[i]);
    }
    if (sim->rules.ecc_dword) {
        memcpy(hi, lo, c);
        sim->state[cell] = CELL_ECC;
    } else if (two_sided && memcmp(hi, lo, c) != 0) {
        sim->state[cell] = CELL_WEAK;
    } else {
        memcpy(hi, lo, c);
        sim->state[cell] = CELL_PROGRAMMED;
    }
}

static km_flash_result_t prv_program(void *ctx, uint32_t offset, const void *data, uint32_t len)
{
    km_nor_sim_t *sim = ctx;
    const uint32_t c = sim->cfg.prog_size;
    if (sim->dead) {
        return KM_FLASH_ERR_PROGRAM;
    }
    if (len == 0u || offset % c != 0u || len % c != 0u || offset > prv_total(sim) ||
        len > prv_total(sim) - offset) {
        sim->count.align_errors++;
        return KM_FLASH_ERR_ALIGN;
    }
    const uint32_t op = sim->ops++;
    const bool cut = (op == sim->cut_at);
    const uint8_t *src = data;
    const uint32_t first = offset / c;
    const uint32_t n = len / c;
    sim->count.programs++;
    for (uint32_t i = 0; i < n; i++) {
        const uint32_t cell = first + i;
        const bool clean = (sim->state[cell] == CELL_ERASED);
        if (!clean) {
            sim->count.violations++;
        }
        if (!prv_check_erased(sim, cell)) {
            sim->count.illegal++;
            if (cut) {
                sim->dead = true;
                sim->cut_was_erase = false;
            }
            return KM_FLASH_ERR_PROGRAM;
        }
        if (!clean) {
            prv_program_over(sim, cell, &src[i * c]);
        } else if (cut && i + 1u == n) {
            prv_tear_cell(sim, cell, &src[i * c], sim->cut_prog);
        } else {
            memcpy(&sim->data[cell * c], &src[i * c], c);
            sim->state[cell] = CELL_PROGRAMMED;
        }
        if (cut && i + 1u == n) {
            sim->dead = true;
            sim->cut_was_erase = false;
            return KM_FLASH_ERR_PROGRAM;
        }
    }
    return KM_FLASH_OK;
}

static void prv_erase_cell(km_nor_sim_t *sim, uint32_t cell)
{
    const uint32_t c = sim->cfg.prog_size;
    memset(&sim->data[cell * c], 0xFF, c);
    sim->state[cell] = CELL_ERASED;
}

/* A partly erased cell: erase only sets bits, so garbage = old | random. */
static void prv_garbage_cell(km_nor_sim_t *sim, uint32_t cell)
{
    const uint32_t c = sim->cfg.prog_size;
    uint8_t *d = &sim->data[cell * c];
    for (uint32_t i = 0; i < c; i++) {
        d[i] = (uint8_t)(d[i] | (uint8_t)prv_rand(sim));
    }
    if (prv_is_all_ones(d, c) && (prv_rand(sim) & 3u) != 0u) {
        sim->state[cell] = CELL_ERASED;
    } else if ((prv_rand(sim) & 3u) == 0u) {
        sim->state[cell] = CELL_ECC;
    } else {
        sim->state[cell] = CELL_TORN_MIXED;
    }
}

/* A cell the erase left weak: the high side all ones, the low side what it
 * held; a cell that was erased stays erased. */
static void prv_weak_erase_cell(km_nor_sim_t *sim, uint32_t cell)
{
    const uint32_t c = sim->cfg.prog_size;
    const uint8_t st = sim->state[cell];
    if (st == CELL_ERASED) {
        return;
    }
    if (st != CELL_UNSTABLE && st != CELL_WEAK) {
        memcpy(&sim->alt[cell * c], &sim->data[cell * c], c);
    }
    memset(&sim->data[cell * c], 0xFF, c);
    sim->state[cell] = CELL_WEAK;
}

static km_flash_result_t prv_erase(void *ctx, uint32_t page)
{
    km_nor_sim_t *sim = ctx;
    if (sim->dead) {
        return KM_FLASH_ERR_ERASE;
    }
    if (page >= sim->cfg.page_count) {
        sim->count.align_errors++;
        return KM_FLASH_ERR_ALIGN;
    }
    const uint32_t op = sim->ops++;
    const uint32_t cells = sim->cfg.page_size / sim->cfg.prog_size;
    const uint32_t first = page * cells;
    sim->count.erases++;
    sim->count.page_erases[page]++;
    if (op != sim->cut_at) {
        for (uint32_t i = 0; i < cells; i++) {
            prv_erase_cell(sim, first + i);
        }
        return KM_FLASH_OK;
    }
    for (uint32_t i = 0; i < cells; i++) {
        const uint32_t cell = first + i;
        switch (sim->cut_erase) {
        case KM_NOR_ERASE_NOT_DONE:
            break;
        case KM_NOR_ERASE_DONE:
            prv_erase_cell(sim, cell);
            break;
        case KM_NOR_ERASE_HALF:
            if (i < cells / 2u) {
                prv_erase_cell(sim, cell);
            }
            break;
        case KM_NOR_ERASE_GARBAGE:
            prv_garbage_cell(sim, cell);
            break;
        case KM_NOR_ERASE_WEAK:
            prv_weak_erase_cell(sim, cell);
            break;
        case KM_NOR_ERASE_MIXED:
        default: {
            const uint32_t r = prv_rand(sim) % 3u;
            if (r == 1u) {
                prv_erase_cell(sim, cell);
            } else if (r == 2u) {
                prv_garbage_cell(sim, cell);
            }
            break;
        }
        }
    }
    sim->dead = true;
    sim->cut_was_erase = true;
    return KM_FLASH_ERR_ERASE;
}

static km_flash_result_t prv_read(void *ctx, uint32_t offset, void *data, uint32_t len)
{
    km_nor_sim_t *sim = ctx;
    const uint32_t c = sim->cfg.prog_size;
    uint8_t *dst = data;
    if (sim->dead) {
        memset(dst, 0xFF, len);
        return KM_FLASH_ERR_ECC;
    }
    if (offset > prv_total(sim) || len > prv_total(sim) - offset) {
        sim->count.align_errors++;
        return KM_FLASH_ERR_ALIGN;
    }
    sim->count.reads++;
    km_flash_result_t r = KM_FLASH_OK;
    /* One draw per cell per read, so a read shows one consistent value of
     * each weak cell; the next read draws again. */
    uint32_t at = offset;
    while (at < offset + len) {
        const uint32_t cell = at / c;
        uint8_t now[8];
        if (!prv_read_cell(sim, cell, now)) {
            r = KM_FLASH_ERR_ECC;
        }
        const uint32_t end = (cell + 1u) * c;
        for (; at < end && at < offset + len; at++) {
            dst[at - offset] = now[at - cell * c];
        }
    }
    return r;
}

bool km_nor_sim_init(km_nor_sim_t *sim, const km_nor_sim_config_t *cfg, km_flash_t *flash)
{
    const uint32_t c = cfg->prog_size;
    if ((c != 2u && c != 4u && c != 8u) || cfg->page_size == 0u || cfg->page_size % c != 0u ||
        cfg->page_count == 0u || cfg->page_count > KM_NOR_SIM_MAX_PAGES ||
        cfg->page_size > KM_NOR_SIM_MAX_BYTES / cfg->page_count) {
        return false;
    }
    memset(sim, 0, sizeof *sim);
    sim->cfg = *cfg;
    sim->cut_at = KM_NOR_SIM_NO_CUT;
    sim->rng = 0x2545F491u;
    const uint32_t total = prv_total(sim);
    memset(sim->data, cfg->fill, total);
    /* A page that ships as 0x00 (QEMU nRF51) is not erased: programming it
     * before an erase is refused, as on the part. */
    const uint8_t st = (cfg->fill == 0xFFu) ? CELL_ERASED : CELL_PROGRAMMED;
    memset(sim->state, st, total / c);
    km_nor_sim_bind(sim, flash);
    return true;
}

void km_nor_sim_bind(km_nor_sim_t *sim, km_flash_t *flash)
{
    flash->page_size = sim->cfg.page_size;
    flash->prog_size = sim->cfg.prog_size;
    flash->page_count = sim->cfg.page_count;
    flash->erase = prv_erase;
    flash->program = prv_program;
    flash->read = prv_read;
    flash->ctx = sim;
}

void km_nor_sim_arm_cut(km_nor_sim_t *sim, uint32_t op_index, km_nor_prog_outcome_t prog,
                        km_nor_erase_outcome_t erase)
{
    sim->cut_at = op_index;
    sim->cut_prog = prog;
    sim->cut_erase = erase;
}

void km_nor_sim_power_cycle(km_nor_sim_t *sim)
{
    sim->dead = false;
    sim->cut_at = KM_NOR_SIM_NO_CUT;
    sim->ops = 0;
}

void km_nor_sim_seed(km_nor_sim_t *sim, uint32_t seed)
{
    sim->rng = (seed == 0u) ? 0x2545F491u : seed;
}

void km_nor_sim_set_rules(km_nor_sim_t *sim, const km_nor_sim_rules_t *rules)
{
    sim->rules = *rules;
}

void km_nor_sim_set_weak_reads(km_nor_sim_t *sim, km_nor_weak_reads_t how)
{
    sim->weak_reads = how;
}

bool km_nor_sim_cut_fired(const km_nor_sim_t *sim)
{
    return sim->dead;
}

uint32_t km_nor_sim_ops(const km_nor_sim_t *sim)
{
    return sim->ops;
}

const char *km_nor_prog_outcome_name(km_nor_prog_outcome_t o)
{
    static const char *const names[] = {"not-done",      "done",     "torn-ones", "torn-mixed",
                                        "torn-unstable", "torn-ecc", "torn-weak"};
    return (o < KM_NOR_PROG_OUTCOMES) ? names[o] : "?";
}

const char *km_nor_erase_outcome_name(km_nor_erase_outcome_t o)
{
    static const char *const names[] = {"not-done", "done", "half", "garbage", "mixed", "weak"};
    return (o < KM_NOR_ERASE_OUTCOMES) ? names[o] : "?";
}
