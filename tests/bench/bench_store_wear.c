/* SPDX-License-Identifier: Apache-2.0 */
/* Wear benchmark of the store on the NOR simulator: erases per 10,000
 * commits (single-register, multi-register, each after a reboot), erase
 * spread over pages, flash bytes programmed per commit, erases per
 * committing boot, flash operations of a boot without a commit, and the
 * worst-case commit latency in flash operations. Prints the figures; fails
 * only on a wrong result (a value lost, a boot that touches flash, an
 * illegal program or a program onto a touched cell), never on the figures
 * themselves. The figures of the store before the dense deltas are in
 * docs/store.md ("Wear figures"), measured with this program at 1e6a7fb. */
#include <stdio.h>
#include <string.h>

#include "../support/km_store_test_schema.h"
#include "km_nor_sim.h"
#include "km_store.h"

#define NKEYS (sizeof k_test_keys / sizeof k_test_keys[0])
#define COMMITS 10000u

static km_nor_sim_t s_sim;
static km_flash_t s_flash;
static km_store_t s_store;
static uint32_t s_model[NKEYS];
static int s_wrong;

typedef enum { MODE_SINGLE, MODE_MULTI, MODE_REBOOT } prv_mode_t;

typedef struct {
    uint32_t erases, programs, min_page, max_page, worst_ops, worst_erases, boots;
    uint32_t bytes; /* programmed */
} prv_figures_t;

static uint32_t prv_ops(void)
{
    return s_sim.count.programs + s_sim.count.erases;
}

static void prv_mount(void)
{
    km_nor_sim_power_cycle(&s_sim);
    const uint32_t before = prv_ops();
    (void)km_store_mount(&s_store, &s_flash, &k_test_schema, NULL);
    if (prv_ops() != before) {
        printf("WRONG: mount issued %u flash operations\n", prv_ops() - before);
        s_wrong = 1;
    }
}

static void prv_run(const km_nor_sim_config_t *cfg, prv_mode_t mode, int maintain, prv_figures_t *fig)
{
    km_nor_sim_init(&s_sim, cfg, &s_flash);
    (void)km_store_mount(&s_store, &s_flash, &k_test_schema, NULL);
    for (unsigned i = 0; i < NKEYS; i++) {
        s_model[i] = k_test_keys[i].def;
    }
    memset(fig, 0, sizeof *fig);
    fig->boots = 1u;
    for (uint32_t n = 0; n < COMMITS; n++) {
        uint8_t keys[4];
        uint32_t vals[4];
        const uint32_t k = (mode == MODE_MULTI) ? 4u : 1u;
        for (uint32_t j = 0; j < k; j++) {
            const uint32_t i = (n * 5u + j) % NKEYS;
            keys[j] = k_test_keys[i].key;
            vals[j] = (n + 1u) * 3u + j;
            s_model[i] = vals[j];
        }
        if (mode == MODE_REBOOT && n > 0u) {
            prv_mount();
            fig->boots++;
        }
        const uint32_t before = prv_ops(), before_e = s_sim.count.erases;
        if (km_store_commit(&s_store, keys, vals, k) != KM_STORE_OK) {
            printf("WRONG: commit %u failed\n", n);
            s_wrong = 1;
            return;
        }
        const uint32_t ops = prv_ops() - before;
        /* The first commit on blank flash erases a page in any design:
         * the worst case counts the commits after it. */
        if (n > 0u && ops > fig->worst_ops) {
            fig->worst_ops = ops;
            fig->worst_erases = s_sim.count.erases - before_e;
        }
        if (maintain) {
            while (km_store_maintain(&s_store)) {
            }
        }
    }
    prv_mount();
    for (unsigned i = 0; i < NKEYS; i++) {
        uint32_t v = 0;
        if (!km_store_get(&s_store, k_test_keys[i].key, &v) || v != s_model[i]) {
            printf("WRONG: key 0x%02X lost after %u commits\n", k_test_keys[i].key, COMMITS);
            s_wrong = 1;
        }
    }
    if (s_sim.count.illegal != 0u || s_sim.count.align_errors != 0u || s_sim.count.violations != 0u) {
        printf("WRONG: illegal program issued\n");
        s_wrong = 1;
    }
    fig->erases = s_sim.count.erases;
    fig->programs = s_sim.count.programs;
    fig->bytes = s_sim.count.programs * cfg->prog_size;
    fig->min_page = 0xFFFFFFFFu;
    for (uint32_t p = 0; p < cfg->page_count; p++) {
        const uint32_t e = s_sim.count.page_erases[p];
        fig->min_page = (e < fig->min_page) ? e : fig->min_page;
        fig->max_page = (e > fig->max_page) ? e : fig->max_page;
    }
}

/* A boot that commits nothing, with the idle loop calling maintain. */
static uint32_t prv_idle_boot_ops(const km_nor_sim_config_t *cfg, uint32_t prior_commits)
{
    km_nor_sim_init(&s_sim, cfg, &s_flash);
    (void)km_store_mount(&s_store, &s_flash, &k_test_schema, NULL);
    for (uint32_t n = 0; n < prior_commits; n++) {
        const uint8_t key = 0x12;
        const uint32_t v = n + 1u;
        (void)km_store_commit(&s_store, &key, &v, 1);
    }
    km_nor_sim_power_cycle(&s_sim);
    const uint32_t before = prv_ops();
    (void)km_store_mount(&s_store, &s_flash, &k_test_schema, NULL);
    for (int i = 0; i < 1000; i++) {
        (void)km_store_maintain(&s_store);
    }
    const uint32_t ops = prv_ops() - before;
    if (ops != 0u) {
        printf("WRONG: a boot without a commit issued %u flash operations\n", ops);
        s_wrong = 1;
    }
    return ops;
}

int main(void)
{
    static const struct {
        const char *name;
        km_nor_sim_config_t cfg;
    } geoms[] = {
        {"STM32G0 2 KiB/8 B x2", {2048u, 8u, 2u, 0xFFu}},
        {"STM32F0 1 KiB/2 B x2", {1024u, 2u, 2u, 0xFFu}},
        {"nRF51   1 KiB/4 B x2", {1024u, 4u, 2u, 0xFFu}},
        {"STM32G031 2 KiB/8 B x3", {2048u, 8u, 3u, 0xFFu}}, /* as boards/stm32g031 ships */
        {"STM32G0 2 KiB/8 B x4", {2048u, 8u, 4u, 0xFFu}},
    };
    static const char *const modes[] = {"single-register", "4-register", "1-reg, reboot each"};
    printf("store wear, %u commits per row, schema of %u persisted registers\n", COMMITS, (unsigned)NKEYS);
    printf("erases = per %u commits; B/commit = flash bytes programmed per commit, snapshots\n"
           "included; per boot = erases per committing boot (rows with a reboot before each\n"
           "commit: every committing boot costs one erase, docs/store.md says why no store\n"
           "can do with less under the simulator's fault model)\n",
           COMMITS);
    printf("%-22s %-19s %-8s %7s %8s %8s %8s %8s  %s\n", "geometry", "commits", "maintain", "erases",
           "page min", "page max", "B/commit", "per boot", "worst commit after the first");
    for (unsigned g = 0; g < sizeof geoms / sizeof geoms[0]; g++) {
        for (unsigned m = 0; m < 3; m++) {
            for (int maint = 0; maint < 2; maint++) {
                prv_figures_t f;
                prv_run(&geoms[g].cfg, (prv_mode_t)m, maint, &f);
                char per_boot[16] = "       -";
                if (f.boots > 1u) {
                    (void)snprintf(per_boot, sizeof per_boot, "%5u.%02u", f.erases / f.boots,
                                   (f.erases % f.boots) * 100u / f.boots);
                }
                printf("%-22s %-19s %-8s %7u %8u %8u %5u.%02u %s  %u ops (%u erase)\n", geoms[g].name,
                       modes[m], maint ? "idle" : "none", f.erases, f.min_page, f.max_page, f.bytes / COMMITS,
                       (f.bytes % COMMITS) / (COMMITS / 100u), per_boot, f.worst_ops, f.worst_erases);
            }
        }
        printf("%-22s flash ops of a boot without a commit (blank / after 500 commits): %u / %u\n",
               geoms[g].name, prv_idle_boot_ops(&geoms[g].cfg, 0), prv_idle_boot_ops(&geoms[g].cfg, 500));
    }
    printf(s_wrong ? "RESULT: WRONG\n" : "RESULT: ok\n");
    return s_wrong;
}
