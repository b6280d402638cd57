/* NOR flash simulator for host tests: a km_flash_t that keeps the rules of a
 * real flash controller and can cut power at any program or erase.
 *
 * Rules enforced (each violation is refused and counted, as a controller's
 * PROGERR/PGERR would be):
 *  - program only whole, aligned cells inside the region (else ERR_ALIGN);
 *  - program only onto an erased cell (else ERR_PROGRAM): a cell that was
 *    programmed, torn with bits cleared, or left with an ECC error since its
 *    page's last erase is not erased;
 *  - erase is per page; reads of a cell torn with ECC report ERR_ECC.
 * A "torn to all ones" cell reads 0xFF and passes the controller's erased
 * check (STM32G0 PROGERR looks at the cell's content), so programming it again
 * is legal here and lands the new value.
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
    KM_NOR_PROG_NOT_DONE = 0, /* power gone before the program started */
    KM_NOR_PROG_DONE,         /* programmed fully, power gone right after */
    KM_NOR_PROG_TORN_ONES,    /* no bit moved yet: reads all ones */
    KM_NOR_PROG_TORN_MIXED,   /* some of the bits to clear are cleared */
    KM_NOR_PROG_TORN_UNSTABLE,/* each read returns the target or a mix, at random */
    KM_NOR_PROG_TORN_ECC,     /* reads report an uncorrectable ECC error */
    KM_NOR_PROG_OUTCOMES
} km_nor_prog_outcome_t;

typedef enum {
    KM_NOR_ERASE_NOT_DONE = 0, /* page untouched */
    KM_NOR_ERASE_DONE,         /* page erased, power gone right after */
    KM_NOR_ERASE_HALF,         /* first half of the cells erased, the rest old */
    KM_NOR_ERASE_GARBAGE,      /* every cell has random bits set, some ECC-bad */
    KM_NOR_ERASE_MIXED,        /* each cell at random old, erased or garbage */
    KM_NOR_ERASE_OUTCOMES
} km_nor_erase_outcome_t;

typedef struct {
    uint32_t page_size;  /* 2048 STM32G0, 1024 F0 and nRF51 */
    uint32_t prog_size;  /* 8 STM32G0, 2 F0, 4 nRF51 */
    uint32_t page_count;
    uint8_t fill;        /* initial content: 0xFF shipped part, 0x00 QEMU nRF51 */
} km_nor_sim_config_t;

typedef struct {
    uint32_t programs;        /* program calls that reached the array */
    uint32_t erases;
    uint32_t reads;
    uint32_t illegal;         /* refused programs: cell not erased */
    uint32_t align_errors;    /* refused calls: misaligned or out of region */
    uint32_t page_erases[KM_NOR_SIM_MAX_PAGES];
} km_nor_sim_counters_t;

typedef struct {
    km_nor_sim_config_t cfg;
    km_nor_sim_counters_t count;
    uint32_t ops;             /* programs + erases since the last power cycle */
    uint32_t cut_at;
    km_nor_prog_outcome_t cut_prog;
    km_nor_erase_outcome_t cut_erase;
    bool dead;
    bool cut_was_erase;       /* kind of the op the cut fell on */
    uint32_t rng;
    uint8_t data[KM_NOR_SIM_MAX_BYTES];
    uint8_t alt[KM_NOR_SIM_MAX_BYTES];    /* target value of an unstable cell */
    uint8_t state[KM_NOR_SIM_MAX_CELLS];  /* km_nor_cell_t per cell */
} km_nor_sim_t;

/* Sets up a simulated region and fills *flash to reach it. Returns false if
 * the geometry is not supported. */
bool km_nor_sim_init(km_nor_sim_t *sim, const km_nor_sim_config_t *cfg, km_flash_t *flash);
/* Re-points *flash at sim (after the sim struct was copied). */
void km_nor_sim_bind(km_nor_sim_t *sim, km_flash_t *flash);
void km_nor_sim_arm_cut(km_nor_sim_t *sim, uint32_t op_index,
                        km_nor_prog_outcome_t prog, km_nor_erase_outcome_t erase);
/* Power returns: the flash works again, no cut armed, op count restarts. */
void km_nor_sim_power_cycle(km_nor_sim_t *sim);
void km_nor_sim_seed(km_nor_sim_t *sim, uint32_t seed);
/* True if the op that was armed happened (the cut fired). */
bool km_nor_sim_cut_fired(const km_nor_sim_t *sim);
/* Program-or-erase ops issued since the last power cycle. */
uint32_t km_nor_sim_ops(const km_nor_sim_t *sim);
const char *km_nor_prog_outcome_name(km_nor_prog_outcome_t o);
const char *km_nor_erase_outcome_name(km_nor_erase_outcome_t o);

#endif
