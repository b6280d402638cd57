/* SPDX-License-Identifier: Apache-2.0 */
/* Power-cut and reset runner for the trial of an image (docs/update.md §3a,
 * §7). A servo is a flash region (the NOR simulator), the words its
 * bootloader and application share in RAM, and an application that is
 * good (it serves the bus and confirms its start), hangs or crashes at
 * start (it never confirms; its trial ends in a reset: the watchdog, the
 * nRF51 trial timer or its fault). Each scenario is a random life of
 * resets that keep RAM (watchdog, fault, the standard restart, a reset in
 * the middle of a flash operation) and power cuts that do not (RAM then
 * reads garbage, an operation under way is cut with a random outcome of
 * the simulator), during trial starts, confirmed runs and updates sent
 * through the bootloader's own dispatcher (km_boot_serve: BEGIN, blocks,
 * VERIFY, COMMIT, START). At every boot the bootloader's decision
 * (km_boot_check, km_boot_entry, km_boot_decide) is taken and required:
 *  (a) it starts only a complete image, byte for byte one that was sent;
 *  (b) an image is never started more than KM_BOOT_TRIAL_MAX times in a
 *      row without confirming, unless a power cut, COMMIT or START came
 *      between (those give it new tries): after that, update mode;
 *  (c) a confirmed start that resets (RAM kept) starts again, and a start
 *      that asked for update mode (0x78 ENTER) gets it;
 *  (d) the user-data pages never change, no cell is programmed that was
 *      not cleanly erased;
 *  (e) at the end, with resets only, the servo settles within
 *      KM_BOOT_TRIAL_MAX + 1 boots either running a good image that
 *      confirmed or in update mode, and from update mode an update to the
 *      good image completes and that image starts and confirms.
 * Figures are printed on every run. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "km_boot_check.h"
#include "km_boot_serve.h"
#include "km_boot_trial.h"
#include "km_store.h"
#include "km_store_test_schema.h"
#include "km_update_proto.h"
#include "km_update_rig.h"

#define PRV_RAM_LO 0x20000000u
#define PRV_RAM_HI 0x20001FE0u
#define PRV_SCENARIOS 400u
#define PRV_STEPS 60u

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

enum { KIND_GOOD, KIND_HANG, KIND_CRASH, KINDS };

static rig_t s_r;
static km_boot_shared_t s_ram;
static km_boot_serve_t s_serve;
static rig_image_t s_img[KINDS];
static uint8_t s_store_snapshot[KM_NOR_SIM_MAX_BYTES];
static uint32_t s_rng;

/* What the life so far requires of the next boot. */
static uint32_t s_unconfirmed; /* trial starts in a row since the last new-tries point */
static bool s_expect_run;      /* a confirmed start was reset, RAM kept */
static bool s_expect_asked;    /* ENTER, RAM kept */

static unsigned long s_boots, s_runs[KINDS], s_stays[4], s_power_cuts, s_resets, s_flash_cuts;
static unsigned long s_updates, s_confirms, s_settled_running, s_settled_update, s_max_in_row;
static unsigned long s_fail[5];
static const char *s_where;
static uint32_t s_seed;

/* Counts an invariant failure; prints the first 20. */
static void prv_fail(int kind, const char *what)
{
    s_fail[kind]++;
    if (s_fail[0] + s_fail[1] + s_fail[2] + s_fail[3] + s_fail[4] <= 20u) {
        fprintf(stderr, "INVARIANT (%c) %s: %s, seed %u\n", 'a' + kind, what, s_where, s_seed);
    }
}

/* A draw in [0, n) from the scenario's xorshift. */
static uint32_t prv_rand(uint32_t n)
{
    s_rng ^= s_rng << 13;
    s_rng ^= s_rng >> 17;
    s_rng ^= s_rng << 5;
    return s_rng % n;
}

/* ---- images: a rig image with a sound vector table ---------------------- */

/* Image `kind`: `length` bytes, a sound vector table, its CRCs. */
static void prv_make(int kind, uint32_t length, uint32_t seed)
{
    rig_image_t *im = &s_img[kind];
    rig_make_image(im, length, 0x00100000u | ((uint32_t)kind << 8) | seed, KM_MODEL_STM32G031, seed);
    rig_set_entry(im, PRV_RAM_HI, RIG_BASE + KM_IMAGE_VECTORS + 0xC1u);
}

/* The kind of image the region holds byte for byte, or -1. The commit
 * cell is left out: the boot check has just read it as the magic, and a
 * cut that tore it unstable may read otherwise now (the rest was read
 * back and verified before it was programmed). */
static int prv_region_kind(void)
{
    uint8_t buf[RIG_MAX_IMAGE];
    const uint32_t cell = s_r.whole.prog_size;
    for (int k = 0; k < KINDS; k++) {
        const rig_image_t *im = &s_img[k];
        if (s_r.region.read(s_r.region.ctx, cell, buf, im->length - cell) == KM_FLASH_OK &&
            memcmp(buf, im->bytes + cell, im->length - cell) == 0) {
            return k;
        }
    }
    return -1;
}

/* ---- RAM ------------------------------------------------------------------ */

/* A power cut: RAM reads garbage; now and then garbage that is a valid
 * count (the worst case: fewer tries than a fresh start). */
static void prv_power_cut(void)
{
    uint32_t *w = (uint32_t *)(void *)&s_ram;
    for (size_t i = 0; i < sizeof s_ram / 4u; i++) {
        w[i] = prv_rand(0xFFFFFFFFu);
    }
    const uint32_t pick = prv_rand(16u);
    if (pick == 0u) {
        memset(&s_ram, 0, sizeof s_ram);
    } else if (pick == 1u) {
        s_ram.attempts = prv_rand(KM_BOOT_TRIAL_MAX + 1u);
        s_ram.attempts_check = s_ram.attempts ^ KM_BOOT_TRIAL_KEY;
    }
    km_nor_sim_power_cycle(&s_r.sim);
    s_power_cuts++;
    s_unconfirmed = 0u;
    s_expect_run = false;
    s_expect_asked = false;
}

/* A reset that keeps RAM: the watchdog, a fault, the standard restart. */
static void prv_reset(void)
{
    km_nor_sim_power_cycle(&s_r.sim); /* the flash controller starts over */
    s_resets++;
}

/* ---- the bootloader ------------------------------------------------------- */

/* (d): user-data pages as the prologue left them, the flash rules kept. */
static void prv_check_store(void)
{
    const uint32_t off = s_r.region_pages * s_r.whole.page_size;
    const uint32_t n = (s_r.whole.page_count - s_r.region_pages) * s_r.whole.page_size;
    if (memcmp(s_r.sim.data + off, s_store_snapshot, n) != 0) {
        prv_fail(3, "store pages changed");
    }
    if (s_r.sim.count.violations != 0u || s_r.sim.count.align_errors != 0u) {
        prv_fail(3, "program onto a cell not cleanly erased, or outside the region");
    }
}

/* A reset into the bootloader: its decision, checked against (a)-(c).
 * Returns the kind started, or -1 for update mode (a session opened). */
static int prv_boot(void)
{
    km_image_header_t h;
    km_boot_entry_t e;
    const bool ok = km_boot_check(&s_r.region, &s_r.target, &h) &&
                    km_boot_entry(&s_r.region, &h, PRV_RAM_LO, PRV_RAM_HI, &e);
    const km_boot_decision_t d = km_boot_decide(&s_ram, ok);
    s_ram.boot_version = 0x10u;
    s_ram.check = ~0x10u;
    s_boots++;
    prv_check_store();
    if (s_expect_run && d != KM_BOOT_RUN) {
        prv_fail(2, "a confirmed start, reset, did not start again");
    }
    if (s_expect_asked && d != KM_BOOT_STAY_ASKED) {
        prv_fail(2, "ENTER did not give update mode");
    }
    s_expect_run = false;
    s_expect_asked = false;
    if (d != KM_BOOT_RUN) {
        s_stays[d]++;
        km_update_init(&s_serve.upd, &s_r.region, &s_r.target);
        return -1;
    }
    const int kind = prv_region_kind();
    if (kind < 0) {
        prv_fail(0, "starts an image that is not one that was sent, byte for byte");
        return -1;
    }
    s_runs[kind]++;
    s_ram.app_running = KM_BOOT_APP_MAGIC;
    return kind;
}

/* ---- the master, through the bootloader's dispatcher ---------------------- */

/* One broadcast frame through the bootloader's dispatcher. */
static void prv_frame(uint8_t cmd, const uint8_t *body, uint8_t n)
{
    const km_frame_view_t v = {
        .id = KM_ID_BROADCAST, .cmd = cmd, .body_len = n, .body = body, .end_tick = 0u};
    km_boot_reply_t r;
    km_boot_serve(&s_serve, &v, &r);
}

/* Step k of an update to image im (BEGIN, blocks, VERIFY, COMMIT). */
static void prv_update_step(const rig_image_t *im, uint32_t k)
{
    uint8_t body[KM_BODY_MAX_TEST];
    const uint32_t blocks = rig_blocks(im);
    if (k == 0u) {
        body[0] = KM_UPD_SUB_BEGIN;
        memcpy(body + 1, im->bytes, KM_IMAGE_HEADER_SIZE);
        prv_frame(KM_CMD_UPDATE, body, (uint8_t)(1u + KM_IMAGE_HEADER_SIZE));
    } else if (k <= blocks) {
        prv_frame(KM_CMD_UPDATE, body, rig_write_body(im, k - 1u, body));
    } else {
        body[0] = k == blocks + 1u ? KM_UPD_SUB_VERIFY : KM_UPD_SUB_COMMIT;
        prv_frame(KM_CMD_UPDATE, body, 1u);
    }
}

/* 0x78 START: the image gets new tries (§3a). */
static void prv_start_frame(void)
{
    static const uint8_t k_start[5] = {KM_UPD_SUB_START, 0xE1u, 0xE2u, 0xE3u, 0xE4u};
    prv_frame(KM_CMD_UPDATE, k_start, 5u);
}

/* The standard restart (write 0x02): the count is kept. */
static void prv_restart_frame(void)
{
    static const uint8_t k_restart[5] = {0x02u, 0xE1u, 0xE2u, 0xE3u, 0xE4u};
    prv_frame(0x03u, k_restart, 5u);
}

/* An update to `kind`, perhaps cut short: by a power cut or a reset inside
 * a flash operation (a random outcome of the simulator), or by a reset
 * between two steps. Ends with the servo about to boot. */
static void prv_update(int kind)
{
    const rig_image_t *im = &s_img[kind];
    const uint32_t steps = rig_blocks(im) + 3u;
    const uint32_t how = prv_rand(8u);
    const bool power = prv_rand(2u) == 0u;
    if (how < 3u) { /* cut inside a flash operation */
        const bool erase_outcome = prv_rand(4u) == 0u;
        km_nor_sim_arm_cut(&s_r.sim, km_nor_sim_ops(&s_r.sim) + prv_rand(steps * 2u + 8u),
                           (km_nor_prog_outcome_t)prv_rand(KM_NOR_PROG_OUTCOMES),
                           erase_outcome ? (km_nor_erase_outcome_t)prv_rand(KM_NOR_ERASE_OUTCOMES)
                                         : KM_NOR_ERASE_DONE);
    }
    const uint32_t stop_at = how == 3u ? prv_rand(steps) : steps; /* reset between steps */
    s_updates++;
    for (uint32_t k = 0; k < stop_at; k++) {
        prv_update_step(im, k);
        if (km_nor_sim_cut_fired(&s_r.sim)) {
            s_flash_cuts++;
            power ? prv_power_cut() : prv_reset();
            return;
        }
    }
    if (s_serve.upd.state == KM_UPD_STATE_COMMITTED) {
        s_unconfirmed = 0u; /* §3a: a committed image gets new tries */
    }
    km_nor_sim_power_cycle(&s_r.sim); /* an armed cut that did not fire: disarmed */
    const uint32_t then = prv_rand(4u);
    if (then == 0u && stop_at == steps) {
        prv_start_frame();
        s_unconfirmed = 0u;
        prv_reset();
    } else if (then == 1u) {
        prv_restart_frame();
        prv_reset();
    } else if (then == 2u) {
        prv_power_cut();
    } else {
        prv_reset();
    }
}

/* ---- the application ------------------------------------------------------ */

/* What a started image does until the next boot. */
static void prv_app(int kind)
{
    const uint32_t r = prv_rand(10u);
    if (r == 0u) {
        prv_power_cut(); /* before it could confirm */
        return;
    }
    if (kind != KIND_GOOD || r == 1u) {
        /* Hangs (watchdog, trial timer), crashes, or a good one faults early. */
        s_unconfirmed++;
        if (s_unconfirmed > s_max_in_row) {
            s_max_in_row = s_unconfirmed;
        }
        if (s_unconfirmed > KM_BOOT_TRIAL_MAX) {
            prv_fail(1, "an image started more than KM_BOOT_TRIAL_MAX times without confirming");
        }
        prv_reset();
        return;
    }
    km_boot_confirm(&s_ram);
    s_confirms++;
    s_unconfirmed = 0u;
    const uint32_t next = prv_rand(4u);
    if (next == 0u) {
        s_ram.request = KM_BOOT_REQUEST_MAGIC; /* 0x78 ENTER (km_board_boot_request) */
        s_expect_asked = true;
        prv_reset();
    } else if (next == 1u) {
        prv_power_cut();
    } else {
        s_expect_run = true; /* the standard restart, a fault, the watchdog */
        prv_reset();
    }
}

/* ---- one scenario ----------------------------------------------------------- */

/* A fresh servo: user data in the store, no image, power-on RAM. */
static void prv_prologue(const prv_geom_t *g)
{
    rig_init(&s_r, g->page_size, g->cell, g->pages, g->region_pages, g->fill);
    km_nor_sim_set_weak_reads(&s_r.sim, prv_rand(2u) == 0u ? KM_NOR_WEAK_HIGH : KM_NOR_WEAK_LOW);
    km_store_t st;
    (void)km_store_mount(&st, &s_r.store, &k_test_schema, NULL);
    const uint8_t keys[2] = {0x0F, 0x10};
    const uint32_t vals[2] = {7u, 10000u};
    assert_int_equal(km_store_commit(&st, keys, vals, 2u), KM_STORE_OK);
    const uint32_t off = s_r.region_pages * s_r.whole.page_size;
    memcpy(s_store_snapshot, s_r.sim.data + off,
           (s_r.whole.page_count - s_r.region_pages) * s_r.whole.page_size);
    memset(&s_serve, 0, sizeof s_serve);
    s_serve.id = 7u;
    s_serve.shared = &s_ram;
    prv_power_cut(); /* power-on */
    s_unconfirmed = 0u;
}

/* (e): resets only from here; settled within KM_BOOT_TRIAL_MAX + 1 boots,
 * then the good image by an update that nothing interrupts. */
static void prv_settle(void)
{
    int kind = -2;
    for (uint32_t i = 0; i <= KM_BOOT_TRIAL_MAX && kind != -1 && kind != KIND_GOOD; i++) {
        kind = prv_boot();
        if (kind >= 0 && kind != KIND_GOOD) {
            s_unconfirmed++;
            if (s_unconfirmed > KM_BOOT_TRIAL_MAX) {
                prv_fail(1, "settling: started again after KM_BOOT_TRIAL_MAX unconfirmed starts");
            }
            prv_reset();
        }
    }
    if (kind == KIND_GOOD) {
        s_settled_running++;
        km_boot_confirm(&s_ram);
        return;
    }
    if (kind != -1) {
        prv_fail(4, "not settled: neither a good image running nor update mode");
        return;
    }
    s_settled_update++;
    const uint32_t steps = rig_blocks(&s_img[KIND_GOOD]) + 3u;
    for (uint32_t k = 0; k < steps; k++) {
        prv_update_step(&s_img[KIND_GOOD], k);
    }
    prv_start_frame();
    prv_reset();
    if (prv_boot() != KIND_GOOD) {
        prv_fail(4, "the good image, sent from update mode, does not start");
    }
}

/* One random life of PRV_STEPS boots, then the settling of (e). */
static void prv_scenario(const prv_geom_t *g, uint32_t seed)
{
    s_seed = seed;
    s_rng = seed * 2654435761u | 1u;
    prv_prologue(g);
    if (prv_rand(2u) == 0u) { /* a good image to start from, or none */
        const uint32_t steps = rig_blocks(&s_img[KIND_GOOD]) + 3u;
        km_update_init(&s_serve.upd, &s_r.region, &s_r.target);
        for (uint32_t k = 0; k < steps; k++) {
            prv_update_step(&s_img[KIND_GOOD], k);
        }
        km_nor_sim_power_cycle(&s_r.sim);
    }
    for (uint32_t step = 0; step < PRV_STEPS; step++) {
        const int kind = prv_boot();
        if (kind >= 0) {
            prv_app(kind);
            continue;
        }
        const uint32_t what = prv_rand(10u);
        if (what < 6u) {
            const uint32_t pick = prv_rand(4u);
            prv_update(pick < 2u ? KIND_GOOD : (pick == 2u ? KIND_HANG : KIND_CRASH));
        } else if (what == 6u) {
            prv_start_frame();
            s_unconfirmed = 0u;
            prv_reset();
        } else if (what == 7u) {
            prv_restart_frame();
            prv_reset();
        } else if (what == 8u) {
            prv_power_cut();
        } else {
            prv_reset();
        }
    }
    prv_settle();
}

static void test_trial_survives_cuts_and_resets(void **state)
{
    (void)state;
    prv_make(KIND_GOOD, 1500u, 31u);
    prv_make(KIND_HANG, 1300u, 32u);
    prv_make(KIND_CRASH, 1700u, 33u);
    printf("trial runner (docs/update.md section 3a): %u scenarios x %u steps per geometry, "
           "images good %u B, hang %u B, crash %u B, KM_BOOT_TRIAL_MAX %u\n",
           PRV_SCENARIOS, PRV_STEPS, s_img[0].length, s_img[1].length, s_img[2].length, KM_BOOT_TRIAL_MAX);
    for (size_t g = 0; g < sizeof s_geoms / sizeof s_geoms[0]; g++) {
        s_where = s_geoms[g].name;
        for (uint32_t seed = 1; seed <= PRV_SCENARIOS; seed++) {
            prv_scenario(&s_geoms[g], seed + 1000u * (uint32_t)g);
        }
    }
    printf("boots %lu: started good %lu, hang %lu, crash %lu; update mode: no image %lu, asked %lu, "
           "gave up %lu\n",
           s_boots, s_runs[KIND_GOOD], s_runs[KIND_HANG], s_runs[KIND_CRASH], s_stays[KM_BOOT_STAY_NO_IMAGE],
           s_stays[KM_BOOT_STAY_ASKED], s_stays[KM_BOOT_STAY_GAVE_UP]);
    printf("power cuts %lu, resets %lu (flash operations cut %lu), updates %lu, confirmed starts %lu;\n"
           "most unconfirmed starts in a row %lu; settled: running the good image %lu, update mode %lu\n",
           s_power_cuts, s_resets, s_flash_cuts, s_updates, s_confirms, s_max_in_row, s_settled_running,
           s_settled_update);
    printf("invariant failures: (a) image %lu, (b) tries %lu, (c) restart/ENTER %lu, (d) flash %lu, "
           "(e) settle %lu\n",
           s_fail[0], s_fail[1], s_fail[2], s_fail[3], s_fail[4]);
    assert_int_equal(s_fail[0] + s_fail[1] + s_fail[2] + s_fail[3] + s_fail[4], 0);
    assert_int_equal(s_max_in_row, KM_BOOT_TRIAL_MAX); /* the limit was reached, not only obeyed */
    assert_true(s_stays[KM_BOOT_STAY_GAVE_UP] > 0u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_trial_survives_cuts_and_resets),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
