/* SPDX-License-Identifier: Apache-2.0 */
/* Power-cut runner for the firmware update (docs/update.md §7). For each
 * flash geometry and starting point (an old image in place, or a region
 * that never held one), an update is run through its 0x78 frames (BEGIN,
 * every WRITE, VERIFY, COMMIT) and cut:
 *  - at every program and every erase it issues, with every outcome the
 *    NOR simulator models (random and weak outcomes drawn three times: weak
 *    cells read at random, always erased, always programmed), and
 *  - between every two protocol steps (power lost with RAM, nothing torn).
 * After each cut the servo "boots": km_boot_check() and km_boot_entry(),
 * the bootloader's own checks, and km_boot_decide() over the RAM words the
 * cut left as garbage (docs/update.md §3a). Required, every time:
 *  (a) it starts the old image, read back byte for byte, or the new one
 *      only after COMMIT's cell, or it stays in the bootloader: never an
 *      image that is neither, and never the bootloader while the old image
 *      is still intact (a cut before the first erase took effect);
 *  (b) the user-data store's pages are byte-identical and mount the same;
 *  (c) no program onto a cell that was not cleanly erased, no call outside
 *      the region (the simulator's violation and alignment counters);
 *  (d) the update, started again from BEGIN after the reboot (RAM lost),
 *      completes and the new image boots, byte for byte.
 * Figures (cut points, outcomes, boots of each kind, bricks) are printed on
 * every run. `test_update_powercut quick` runs one geometry. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "km_boot_check.h"
#include "km_boot_trial.h"
#include "km_store.h"
#include "km_store_test_schema.h"
#include "km_update_proto.h"
#include "km_update_rig.h"

typedef struct {
    const char *name;
    uint32_t page_size, cell, pages, region_pages;
    uint8_t fill;
} prv_geom_t;

static const prv_geom_t s_geoms[] = {
    {"STM32G0 (2 KiB pages, 8 B cells, ECC rule)", 2048u, 8u, 4u, 2u, 0xFFu},
    {"nRF51 (1 KiB pages, 4 B cells)", 1024u, 4u, 6u, 4u, 0xFFu},
    {"nRF51 in QEMU (never-written flash reads 00)", 1024u, 4u, 6u, 4u, 0x00u},
};

enum { BOOT_OLD, BOOT_NEW, BOOT_LOADER, BOOT_KINDS };
static const char *const k_boot_name[BOOT_KINDS] = {"old image", "new image", "bootloader"};

static rig_t s_base; /* after the prologue: store written, old image (or none) */
static rig_t s_r;    /* the flash under test */
static km_update_t s_u;
static rig_image_t s_old, s_new;
static bool s_has_old;
static bool s_reverse; /* blocks sent last to first */
static uint8_t s_store_snapshot[KM_NOR_SIM_MAX_BYTES];
static uint32_t s_store_values[KM_STORE_MAX_KEYS];

static unsigned long s_cut_points, s_runs, s_bricks, s_boots[BOOT_KINDS], s_recovered;
static unsigned long s_step_cuts;
static unsigned long s_decisions;        /* trial decisions taken over power-cut RAM */
static uint32_t s_garbage = 0x2545F491u; /* xorshift state of that RAM */
static unsigned long s_fail[4];
static const char *s_where;
static uint32_t s_where_i, s_where_o;

static void prv_fail(int kind, const char *what)
{
    s_fail[kind]++;
    if (s_fail[0] + s_fail[1] + s_fail[2] + s_fail[3] <= 20u) {
        fprintf(stderr, "INVARIANT (%c) %s: %s, cut %u outcome %u\n", 'a' + kind, what, s_where, s_where_i,
                s_where_o);
    }
}

/* ---- the update as a master sends it ---------------------------------- */

static uint32_t prv_steps(void)
{
    return 1u + rig_blocks(&s_new) + 2u; /* BEGIN, blocks, VERIFY, COMMIT */
}

/* Runs protocol step k of the update; returns its result. */
static uint8_t prv_step(uint32_t k)
{
    km_update_answer_t a;
    uint8_t body[KM_BODY_MAX_TEST];
    const uint32_t blocks = rig_blocks(&s_new);
    if (k == 0u) {
        body[0] = KM_UPD_SUB_BEGIN;
        memcpy(body + 1, s_new.bytes, KM_IMAGE_HEADER_SIZE);
        km_update_frame(&s_u, body, 1u + KM_IMAGE_HEADER_SIZE, &a);
    } else if (k <= blocks) {
        const uint32_t b = s_reverse ? blocks - k : k - 1u;
        km_update_frame(&s_u, body, rig_write_body(&s_new, b, body), &a);
    } else {
        body[0] = k == blocks + 1u ? KM_UPD_SUB_VERIFY : KM_UPD_SUB_COMMIT;
        km_update_frame(&s_u, body, 1u, &a);
    }
    return a.body[1];
}

static void prv_session(void)
{
    km_update_init(&s_u, &s_r.region, &s_r.target);
}

/* ---- checks after a reboot --------------------------------------------- */

static bool prv_region_is(const rig_image_t *im)
{
    uint8_t buf[RIG_MAX_IMAGE];
    return s_r.region.read(s_r.region.ctx, 0u, buf, im->length) == KM_FLASH_OK &&
           memcmp(buf, im->bytes, im->length) == 0;
}

static uint32_t prv_store_bytes(void)
{
    return (s_r.whole.page_count - s_r.region_pages) * s_r.whole.page_size;
}

static void prv_check_store(void)
{
    const uint32_t off = s_r.region_pages * s_r.whole.page_size;
    if (memcmp(s_r.sim.data + off, s_store_snapshot, prv_store_bytes()) != 0) {
        prv_fail(1, "store pages changed");
        return;
    }
    km_store_t st;
    uint32_t v[KM_STORE_MAX_KEYS] = {0};
    if (km_store_mount(&st, &s_r.store, &k_test_schema, v) != KM_STORE_MOUNT_LOADED ||
        memcmp(v, s_store_values, sizeof v) != 0) {
        prv_fail(1, "store mounts differently");
    }
}

#define PRV_RAM_LO 0x20000000u
#define PRV_RAM_HI 0x20001FE0u

/* The bootloader's checks: the image passes the boot check and its entry
 * (initial SP, reset vector) the entry check. */
static bool prv_checks(km_image_header_t *h)
{
    km_boot_entry_t e;
    return km_boot_check(&s_r.region, &s_r.target, h) &&
           km_boot_entry(&s_r.region, h, PRV_RAM_LO, PRV_RAM_HI, &e);
}

/* §3a: the decision over the RAM words a power cut left (garbage) starts
 * exactly what the checks pass. */
static void prv_decide_after_cut(bool app)
{
    km_boot_shared_t ram;
    uint32_t *w = (uint32_t *)(void *)&ram;
    for (size_t i = 0; i < sizeof ram / 4u; i++) {
        s_garbage ^= s_garbage << 13;
        s_garbage ^= s_garbage >> 17;
        s_garbage ^= s_garbage << 5;
        w[i] = s_garbage;
    }
    s_decisions++;
    if ((km_boot_decide(&ram, app) == KM_BOOT_RUN) != app) {
        prv_fail(0, "the trial decision after a power cut differs from the checks");
    }
}

/* (a): what the bootloader decides now; `old_possible`: no erase of this
 * update has taken effect yet, `new_possible`: COMMIT's cell was reached. */
static void prv_boot(bool new_possible)
{
    km_image_header_t h;
    const bool app = prv_checks(&h);
    /* Twice, so a weak cell that reads differently is caught. */
    km_image_header_t h2;
    const bool app2 = prv_checks(&h2);
    prv_decide_after_cut(app);
    if (app != app2 && s_r.sim.weak_reads != KM_NOR_WEAK_RANDOM) {
        prv_fail(0, "boot decision changes between two reads with pinned weak cells");
    }
    if (!app) {
        s_boots[BOOT_LOADER]++;
        if (s_has_old && s_r.sim.weak_reads != KM_NOR_WEAK_RANDOM && prv_region_is(&s_old)) {
            prv_fail(0, "bootloader while the old image is intact");
        }
        return;
    }
    if (s_has_old && h.version == s_old.version && prv_region_is(&s_old)) {
        s_boots[BOOT_OLD]++;
    } else if (new_possible && h.version == s_new.version && prv_region_is(&s_new)) {
        s_boots[BOOT_NEW]++;
    } else {
        s_bricks++;
        prv_fail(0, "boots an image that is neither the old one nor the committed new one");
    }
}

static void prv_check_flash_rules(void)
{
    if (s_r.sim.count.violations != 0u || s_r.sim.count.align_errors != 0u) {
        prv_fail(2, "program onto a cell not cleanly erased, or outside the region");
    }
}

/* (d): a new session (RAM lost) runs the whole update; it must boot new. */
static void prv_recover(void)
{
    km_nor_sim_power_cycle(&s_r.sim);
    km_nor_sim_set_weak_reads(&s_r.sim, KM_NOR_WEAK_RANDOM);
    prv_session();
    for (uint32_t k = 0; k < prv_steps(); k++) {
        if (prv_step(k) != KM_UPD_OK) {
            prv_fail(3, "the update after the cut did not complete");
            return;
        }
    }
    km_image_header_t h;
    if (!prv_checks(&h) || !prv_region_is(&s_new)) {
        prv_fail(3, "the completed update does not boot the new image");
        return;
    }
    prv_check_store();
    prv_check_flash_rules();
    s_recovered++;
}

/* ---- one run: cut at op i with an outcome ------------------------------ */

static void prv_run_cut(uint32_t i, unsigned outcome, bool erase, unsigned draw)
{
    s_r = s_base;
    rig_bind(&s_r);
    km_nor_sim_seed(&s_r.sim, 0x9E3779B9u ^ (i * 131u + outcome * 7u + draw));
    static const km_nor_weak_reads_t modes[3] = {KM_NOR_WEAK_RANDOM, KM_NOR_WEAK_HIGH, KM_NOR_WEAK_LOW};
    km_nor_sim_set_weak_reads(&s_r.sim, modes[draw % 3u]);
    km_nor_sim_arm_cut(&s_r.sim, i, erase ? KM_NOR_PROG_NOT_DONE : (km_nor_prog_outcome_t)outcome,
                       erase ? (km_nor_erase_outcome_t)outcome : KM_NOR_ERASE_NOT_DONE);
    s_where_i = i;
    s_where_o = outcome;
    prv_session();
    bool commit_reached = false;
    for (uint32_t k = 0; k < prv_steps(); k++) {
        commit_reached = k == prv_steps() - 1u;
        (void)prv_step(k);
        if (km_nor_sim_cut_fired(&s_r.sim)) {
            break; /* the CPU stops with the power */
        }
    }
    km_nor_sim_power_cycle(&s_r.sim);
    s_runs++;
    prv_boot(commit_reached);
    prv_check_store();
    prv_check_flash_rules();
    prv_recover();
}

/* Kind of op i of a clean update (probed with a harmless cut). */
static bool prv_op_is_erase(uint32_t i)
{
    s_r = s_base;
    rig_bind(&s_r);
    km_nor_sim_arm_cut(&s_r.sim, i, KM_NOR_PROG_NOT_DONE, KM_NOR_ERASE_NOT_DONE);
    prv_session();
    for (uint32_t k = 0; k < prv_steps() && !km_nor_sim_cut_fired(&s_r.sim); k++) {
        (void)prv_step(k);
    }
    return s_r.sim.cut_was_erase;
}

static bool prv_random_outcome(unsigned o, bool erase)
{
    return erase ? (o == KM_NOR_ERASE_MIXED || o == KM_NOR_ERASE_WEAK || o == KM_NOR_ERASE_GARBAGE)
                 : (o == KM_NOR_PROG_TORN_UNSTABLE || o == KM_NOR_PROG_TORN_WEAK ||
                    o == KM_NOR_PROG_TORN_MIXED);
}

/* ---- one scenario ------------------------------------------------------ */

static void prv_prologue(const prv_geom_t *g, bool with_old)
{
    rig_init(&s_base, g->page_size, g->cell, g->pages, g->region_pages, g->fill);
    s_r = s_base;
    rig_bind(&s_r);
    /* User data: a session of commits in the store pages. */
    km_store_t st;
    (void)km_store_mount(&st, &s_r.store, &k_test_schema, NULL);
    const uint8_t keys[3] = {0x0F, 0x10, 0x12};
    const uint32_t vals[3] = {7u, 10000u, 350u};
    assert_int_equal(km_store_commit(&st, keys, vals, 3u), KM_STORE_OK);
    const uint8_t key2 = 0x13;
    const uint32_t val2 = 800u;
    assert_int_equal(km_store_commit(&st, &key2, &val2, 1u), KM_STORE_OK);
    /* The old image, put there by an update of its own. */
    s_has_old = with_old;
    if (with_old) {
        rig_image_t keep_new = s_new;
        s_new = s_old;
        prv_session();
        for (uint32_t k = 0; k < prv_steps(); k++) {
            assert_int_equal(prv_step(k), KM_UPD_OK);
        }
        s_new = keep_new;
    }
    km_nor_sim_power_cycle(&s_r.sim);
    s_r.sim.count = (km_nor_sim_counters_t){0};
    s_base = s_r;
    const uint32_t off = s_r.region_pages * s_r.whole.page_size;
    memcpy(s_store_snapshot, s_r.sim.data + off, prv_store_bytes());
    km_store_t st2;
    assert_int_equal(km_store_mount(&st2, &s_r.store, &k_test_schema, s_store_values), KM_STORE_MOUNT_LOADED);
    if (with_old) {
        km_image_header_t h;
        assert_true(prv_checks(&h));
    }
}

static void prv_scenario(const prv_geom_t *g, bool with_old, bool reverse)
{
    s_reverse = reverse;
    prv_prologue(g, with_old);
    /* A clean run: how many flash ops the update issues. */
    s_r = s_base;
    rig_bind(&s_r);
    prv_session();
    for (uint32_t k = 0; k < prv_steps(); k++) {
        assert_int_equal(prv_step(k), KM_UPD_OK);
    }
    const uint32_t ops = km_nor_sim_ops(&s_r.sim);
    const unsigned long runs0 = s_runs, steps0 = s_step_cuts;
    unsigned long boots0[BOOT_KINDS];
    memcpy(boots0, s_boots, sizeof boots0);
    char where[160];
    snprintf(where, sizeof where, "%s, %s, blocks %s", g->name, with_old ? "old image" : "no image",
             reverse ? "last first" : "in order");
    s_where = where;

    for (uint32_t i = 0; i < ops; i++) {
        const bool erase = prv_op_is_erase(i);
        const unsigned n = erase ? KM_NOR_ERASE_OUTCOMES : KM_NOR_PROG_OUTCOMES;
        for (unsigned o = 0; o < n; o++) {
            const unsigned draws = prv_random_outcome(o, erase) ? 3u : 1u;
            for (unsigned d = 0; d < draws; d++) {
                prv_run_cut(i, o, erase, d);
            }
        }
    }
    s_cut_points += ops;

    /* Power lost between protocol steps: nothing torn, RAM gone. */
    for (uint32_t k = 0; k <= prv_steps(); k++) {
        s_r = s_base;
        rig_bind(&s_r);
        prv_session();
        for (uint32_t j = 0; j < k; j++) {
            (void)prv_step(j);
        }
        km_nor_sim_power_cycle(&s_r.sim);
        s_where_i = k;
        s_where_o = 99u;
        const unsigned long before[BOOT_KINDS] = {s_boots[0], s_boots[1], s_boots[2]};
        prv_boot(k == prv_steps());
        /* Exact here: old before BEGIN, new after COMMIT, bootloader between. */
        const int expect =
            k == 0u ? (with_old ? BOOT_OLD : BOOT_LOADER) : (k == prv_steps() ? BOOT_NEW : BOOT_LOADER);
        if (s_boots[expect] != before[expect] + 1u) {
            prv_fail(0, "a step boundary booted the wrong thing");
        }
        prv_check_store();
        prv_check_flash_rules();
        prv_recover();
        s_step_cuts++;
    }
    printf("  %-48s %-9s %-10s: %4u flash ops, %5lu cut runs, %3lu step cuts -> old %lu, bootloader %lu, new "
           "%lu\n",
           g->name, with_old ? "old image" : "no image", reverse ? "last first" : "in order", ops,
           s_runs - runs0, s_step_cuts - steps0, s_boots[BOOT_OLD] - boots0[BOOT_OLD],
           s_boots[BOOT_LOADER] - boots0[BOOT_LOADER], s_boots[BOOT_NEW] - boots0[BOOT_NEW]);
}

static bool s_quick;

static void test_update_survives_every_cut(void **state)
{
    (void)state;
    rig_make_image(&s_old, 1300u, 0x00100100u, KM_MODEL_STM32G031, 11u);
    rig_make_image(&s_new, 1700u, 0x00100200u, KM_MODEL_STM32G031, 22u);
    rig_set_entry(&s_old, PRV_RAM_HI, RIG_BASE + 0x4C1u);
    rig_set_entry(&s_new, PRV_RAM_HI, RIG_BASE + 0x6A1u);
    printf("update power-cut runner (docs/update.md section 7): old image %u B, new %u B (%u blocks)\n",
           s_old.length, s_new.length, rig_blocks(&s_new));
    const size_t ngeoms = s_quick ? 1u : sizeof s_geoms / sizeof s_geoms[0];
    for (size_t g = 0; g < ngeoms; g++) {
        prv_scenario(&s_geoms[g], true, false);
        prv_scenario(&s_geoms[g], false, false);
        if (g == 0u) {
            prv_scenario(&s_geoms[g], true, true);
        }
    }
    printf("total: %lu cut points (flash ops), %lu runs cut at an op, %lu cut between steps;\n"
           "       boots: %lu %s, %lu %s, %lu %s; %lu updates finished after the cut; %lu bricks\n",
           s_cut_points, s_runs, s_step_cuts, s_boots[BOOT_OLD], k_boot_name[BOOT_OLD], s_boots[BOOT_LOADER],
           k_boot_name[BOOT_LOADER], s_boots[BOOT_NEW], k_boot_name[BOOT_NEW], s_recovered, s_bricks);
    printf("       trial decisions over power-cut RAM: %lu, each the checks' verdict\n", s_decisions);
    printf("invariant failures: (a) boot %lu, (b) store %lu, (c) flash rules %lu, (d) recovery %lu\n",
           s_fail[0], s_fail[1], s_fail[2], s_fail[3]);
    assert_int_equal(s_fail[0] + s_fail[1] + s_fail[2] + s_fail[3], 0);
    assert_int_equal(s_bricks, 0);
    assert_int_equal(s_recovered, s_runs + s_step_cuts);
}

int main(int argc, char **argv)
{
    s_quick = argc > 1 && strcmp(argv[1], "quick") == 0;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_update_survives_every_cut),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
