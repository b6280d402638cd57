/* SPDX-License-Identifier: Apache-2.0 */
/* NOR flash simulator for host tests: a km_flash_t that keeps the rules of a
 * real flash controller and can cut power at any program or erase.
 *
 * Rules enforced (each violation is refused and counted, as a controller's
 * PROGERR/PGERR would be):
 *  - program only whole, aligned cells inside the region (else ERR_ALIGN);
 *  - program only onto an erased cell (else ERR_PROGRAM): a cell that was
 *    programmed, torn in any way, or left half erased since its page's last
 *    complete erase is not erased;
 *  - erase is per page; reads of a cell torn with ECC report ERR_ECC.
 *
 * Every program onto a cell that is not cleanly erased is a *violation*
 * (count.violations), whether the controller refuses it or lets it through:
 * a store must never program a cell a past session may have touched. Two
 * switches (km_nor_sim_set_rules) make the controller more like a real one:
 *  - ecc_dword (STM32G0): a 64-bit double word whose program was started
 *    has its ECC partly written and must not be programmed again before an
 *    erase, even if it reads all 0xFF. Programmed again anyway, it reads
 *    with an ECC error from then on.
 *  - content_check: the controller's "is it erased" check reads the cell
 *    (like the G0 PROGERR check and the board driver's check), one read,
 *    with weak cells read as any read is. A cell that reads all 0xFF is
 *    programmed whatever it really is; the result is the AND of what was
 *    there and the new value, and stays weak where the old cell was weak.
 * Without content_check the controller knows each cell's state (ideal
 * check); a "torn to all ones" cell then passes it unless ecc_dword is set.
 *
 * Weak cells (a cut program's KM_NOR_PROG_TORN_WEAK, a cut erase's
 * KM_NOR_ERASE_WEAK) sit between two values, a high one (more bits set: the
 * erased side) and a low one (the programmed side). Each read returns one
 * of them or a mix of the bits in between, drawn from the seeded PRNG; or,
 * with km_nor_sim_set_weak_reads(), always the high or always the low value,
 * so a test can make one mount see "erased" and the next "programmed".
 *
 * Power cuts: km_nor_sim_arm_cut() picks the Nth program-or-erase (0-based,
 * counted from the last power cycle) and what it leaves behind. After the cut
 * the flash is dead: every call fails with no effect until
 * km_nor_sim_power_cycle(). A multi-cell program is cut in its last cell (the
 * ones before it complete); the store programs one cell per call anyway. */
#ifndef KM_NOR_SIM_H
#define KM_NOR_SIM_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"

#define KM_NOR_SIM_MAX_BYTES 8192u
#define KM_NOR_SIM_MAX_PAGES 16u
#define KM_NOR_SIM_MAX_CELLS (KM_NOR_SIM_MAX_BYTES / 2u)
#define KM_NOR_SIM_NO_CUT 0xFFFFFFFFu

typedef enum {
    KM_NOR_PROG_NOT_DONE = 0,  /* power gone before the program started */
    KM_NOR_PROG_DONE,          /* programmed fully, power gone right after */
    KM_NOR_PROG_TORN_ONES,     /* no bit moved yet: reads all ones */
    KM_NOR_PROG_TORN_MIXED,    /* some of the bits to clear are cleared */
    KM_NOR_PROG_TORN_UNSTABLE, /* each read returns the target or a mix, at random */
    KM_NOR_PROG_TORN_ECC,      /* reads report an uncorrectable ECC error */
    KM_NOR_PROG_TORN_WEAK,     /* weak: each read erased, the target, or a mix */
    KM_NOR_PROG_OUTCOMES
} km_nor_prog_outcome_t;

typedef enum {
    KM_NOR_ERASE_NOT_DONE = 0, /* page untouched */
    KM_NOR_ERASE_DONE,         /* page erased, power gone right after */
    KM_NOR_ERASE_HALF,         /* first half of the cells erased, the rest old */
    KM_NOR_ERASE_GARBAGE,      /* every cell has random bits set, some ECC-bad */
    KM_NOR_ERASE_MIXED,        /* each cell at random old, erased or garbage */
    KM_NOR_ERASE_WEAK,         /* every written cell weak: reads old, erased or between */
    KM_NOR_ERASE_OUTCOMES
} km_nor_erase_outcome_t;

typedef struct {
    uint32_t page_size; /* 2048 STM32G0, 1024 F0 and nRF51 */
    uint32_t prog_size; /* 8 STM32G0, 2 F0, 4 nRF51 */
    uint32_t page_count;
    uint8_t fill; /* initial content: 0xFF shipped part, 0x00 QEMU nRF51 */
} km_nor_sim_config_t;

typedef struct {
    bool ecc_dword;     /* STM32G0: a started program makes the cell unprogrammable */
    bool content_check; /* the controller's erased check reads the cell's content */
} km_nor_sim_rules_t;

/* How weak cells read. */
typedef enum {
    KM_NOR_WEAK_RANDOM = 0, /* each read drawn from the PRNG */
    KM_NOR_WEAK_HIGH,       /* always the erased side (a weak program reads 0xFF) */
    KM_NOR_WEAK_LOW,        /* always the programmed side (target, or old content) */
} km_nor_weak_reads_t;

typedef struct {
    uint32_t programs; /* program calls that reached the array */
    uint32_t erases;
    uint32_t reads;
    uint32_t illegal;      /* refused programs: cell not erased */
    uint32_t violations;   /* programs onto a cell not cleanly erased, refused or not */
    uint32_t align_errors; /* refused calls: misaligned or out of region */
    uint32_t page_erases[KM_NOR_SIM_MAX_PAGES];
} km_nor_sim_counters_t;

typedef struct {
    km_nor_sim_config_t cfg;
    km_nor_sim_rules_t rules;
    km_nor_weak_reads_t weak_reads;
    km_nor_sim_counters_t count;
    uint32_t ops; /* programs + erases since the last power cycle */
    uint32_t cut_at;
    km_nor_prog_outcome_t cut_prog;
    km_nor_erase_outcome_t cut_erase;
    bool dead;
    bool cut_was_erase; /* kind of the op the cut fell on */
    uint32_t rng;
    uint8_t data[KM_NOR_SIM_MAX_BYTES];
    uint8_t alt[KM_NOR_SIM_MAX_BYTES];   /* target of an unstable cell, low side of a weak one */
    uint8_t state[KM_NOR_SIM_MAX_CELLS]; /* km_nor_cell_t per cell */
} km_nor_sim_t;

/* Sets up a simulated region and fills *flash to reach it. Returns false if
 * the geometry is not supported. */
bool km_nor_sim_init(km_nor_sim_t *sim, const km_nor_sim_config_t *cfg, km_flash_t *flash);
/* Re-points *flash at sim (after the sim struct was copied). */
void km_nor_sim_bind(km_nor_sim_t *sim, km_flash_t *flash);
void km_nor_sim_arm_cut(km_nor_sim_t *sim, uint32_t op_index, km_nor_prog_outcome_t prog,
                        km_nor_erase_outcome_t erase);
/* Power returns: the flash works again, no cut armed, op count restarts. */
void km_nor_sim_power_cycle(km_nor_sim_t *sim);
void km_nor_sim_seed(km_nor_sim_t *sim, uint32_t seed);
/* Controller rules (default: both off, the ideal state check). */
void km_nor_sim_set_rules(km_nor_sim_t *sim, const km_nor_sim_rules_t *rules);
/* How weak cells read from now on (default KM_NOR_WEAK_RANDOM). */
void km_nor_sim_set_weak_reads(km_nor_sim_t *sim, km_nor_weak_reads_t how);
/* True if the op that was armed happened (the cut fired). */
bool km_nor_sim_cut_fired(const km_nor_sim_t *sim);
/* Program-or-erase ops issued since the last power cycle. */
uint32_t km_nor_sim_ops(const km_nor_sim_t *sim);
const char *km_nor_prog_outcome_name(km_nor_prog_outcome_t o);
const char *km_nor_erase_outcome_name(km_nor_erase_outcome_t o);

#endif
