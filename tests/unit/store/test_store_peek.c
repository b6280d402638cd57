/* SPDX-License-Identifier: Apache-2.0 */
/* km_store_peek (firmware/store/km_store_peek.c, the bootloader's read of
 * ID and baud, docs/update.md §3) against km_store_mount (docs/store.md
 * "Mount"): on stores left by random sessions of random schemas (key lists
 * with and without 0x0F and 0x10, schema versions 1 and 2) with a power cut
 * at a random program or erase and every deterministic outcome of the NOR
 * simulator, on the STM32G0 and nRF51 geometries (erased 0xFF and QEMU's
 * 0x00), the peek says "loaded" exactly when the mount of a {0x0F, 0x10}
 * schema returns LOADED or MIGRATED, with the same values. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "km_nor_sim.h"
#include "km_store.h"
#include "km_store_peek.h"

static km_nor_sim_t s_sim;
static km_flash_t s_flash;
static km_store_t s_store;

static uint32_t s_seed = 1u;
static uint32_t prv_rand(void)
{
    s_seed = s_seed * 1103515245u + 12345u;
    return s_seed >> 8;
}

/* Session schemas: the servo's two keys among others, or one or none of them. */
static const km_store_key_t k_a[] = {{0x0Fu, 0u}, {0x10u, 1152u}, {0x20u, 7u}, {0x21u, 9u}};
static const km_store_key_t k_b[] = {{0x21u, 9u}, {0x10u, 1152u}, {0x30u, 1u}, {0x0Fu, 0u}, {0x31u, 2u}};
static const km_store_key_t k_c[] = {{0x20u, 7u}, {0x0Fu, 0u}};
static const km_store_key_t k_d[] = {{0x40u, 3u}, {0x41u, 4u}};
static const km_store_schema_t k_schemas[] = {
    {k_a, 4u, 1u}, {k_b, 5u, 1u}, {k_c, 2u, 1u}, {k_d, 2u, 1u}, {k_a, 4u, 2u}, {k_b, 5u, 2u},
};

static const km_store_key_t k_boot_keys[] = {{0x0Fu, 0u}, {0x10u, 1152u}};
static const km_store_schema_t k_boot = {k_boot_keys, 2u, 1u};

static unsigned s_loaded;
static unsigned s_defaults;

static void prv_compare(void)
{
    uint32_t mv[2];
    km_store_t m;
    const km_store_mount_t r = km_store_mount(&m, &s_flash, &k_boot, mv);
    static const uint8_t keys[2] = {0x0Fu, 0x10u};
    uint32_t pv[2] = {0u, 1152u};
    const bool got = km_store_peek(&s_flash, 1u, keys, 2u, pv);
    const bool want = r == KM_STORE_MOUNT_LOADED || r == KM_STORE_MOUNT_MIGRATED;
    assert_int_equal(got, want);
    if (want) {
        assert_int_equal(pv[0], mv[0]);
        assert_int_equal(pv[1], mv[1]);
        s_loaded++;
    } else {
        assert_int_equal(pv[0], 0u);
        assert_int_equal(pv[1], 1152u);
        s_defaults++;
    }
}

/* One session: mount with a schema, a few commits, maybe cut. */
static void prv_session(void)
{
    const km_store_schema_t *sc = &k_schemas[prv_rand() % 6u];
    if (prv_rand() % 3u == 0u) {
        km_nor_prog_outcome_t po;
        do {
            po = (km_nor_prog_outcome_t)(prv_rand() % KM_NOR_PROG_OUTCOMES);
        } while (po == KM_NOR_PROG_TORN_UNSTABLE); /* reads at random: no single answer */
        km_nor_sim_arm_cut(&s_sim, prv_rand() % 12u, po,
                           (km_nor_erase_outcome_t)(prv_rand() % KM_NOR_ERASE_OUTCOMES));
    }
    (void)km_store_mount(&s_store, &s_flash, sc, NULL);
    const unsigned commits = prv_rand() % 5u;
    for (unsigned c = 0; c < commits; c++) {
        uint8_t keys[2];
        uint32_t vals[2];
        const uint32_t n = 1u + prv_rand() % 2u;
        for (uint32_t i = 0; i < n; i++) {
            keys[i] = sc->keys[(prv_rand() + i) % sc->count].key;
            vals[i] = prv_rand() % 4u == 0u ? prv_rand() : prv_rand() % 300u;
        }
        if (n == 2u && keys[0] == keys[1]) {
            continue;
        }
        (void)km_store_commit(&s_store, keys, vals, n);
    }
    km_nor_sim_power_cycle(&s_sim);
}

static void test_peek_matches_mount(void **state)
{
    (void)state;
    static const km_nor_sim_config_t k_geo[] = {
        {2048u, 8u, 3u, 0xFFu}, {1024u, 4u, 4u, 0xFFu}, {1024u, 4u, 4u, 0x00u}};
    for (unsigned run = 0; run < 3000u; run++) {
        s_seed = run * 7919u + 1u;
        const km_nor_sim_config_t *g = &k_geo[run % 3u];
        assert_true(km_nor_sim_init(&s_sim, g, &s_flash));
        const km_nor_sim_rules_t rules = {.ecc_dword = g->prog_size == 8u, .content_check = true};
        km_nor_sim_set_rules(&s_sim, &rules);
        km_nor_sim_seed(&s_sim, run + 1u);
        km_nor_sim_set_weak_reads(&s_sim, run % 2u ? KM_NOR_WEAK_HIGH : KM_NOR_WEAK_LOW);
        prv_compare();
        for (unsigned k = 0; k < 20u; k++) {
            prv_session();
            prv_compare();
        }
    }
    printf("store peek vs mount: %u stores with values loaded, %u with defaults, all identical\n", s_loaded,
           s_defaults);
    assert_true(s_loaded > 1000u);
    assert_true(s_defaults > 100u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_peek_matches_mount),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
