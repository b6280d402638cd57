/* SPDX-License-Identifier: Apache-2.0 */
/* NOR simulator tests: the controller rules it must enforce, and each power
 * cut outcome leaving what it claims, for every supported geometry; weak
 * cells (a cut program or erase that reads differently at each read), the
 * STM32G0 ECC double-word rule and the controller's content-reading erased
 * check, each counted as a violation when a program lands on such a cell. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "km_nor_sim.h"

static km_nor_sim_t s_sim;
static km_flash_t s_flash;

static const km_nor_sim_config_t s_geoms[] = {
    {2048u, 8u, 2u, 0xFFu}, /* STM32G0 */
    {1024u, 2u, 4u, 0xFFu}, /* STM32F0 / GD32 */
    {1024u, 4u, 4u, 0xFFu}, /* nRF51 */
};

static void prv_fill(uint8_t *b, uint32_t n, uint8_t v)
{
    memset(b, v, n);
}

static void test_geometry_and_erased_start(void **state)
{
    (void)state;
    for (unsigned g = 0; g < sizeof s_geoms / sizeof s_geoms[0]; g++) {
        assert_true(km_nor_sim_init(&s_sim, &s_geoms[g], &s_flash));
        assert_int_equal(s_flash.page_size, s_geoms[g].page_size);
        assert_int_equal(s_flash.prog_size, s_geoms[g].prog_size);
        assert_int_equal(s_flash.page_count, s_geoms[g].page_count);
        uint8_t b[8];
        assert_int_equal(s_flash.read(s_flash.ctx, 0, b, 8), KM_FLASH_OK);
        for (unsigned i = 0; i < 8; i++) {
            assert_int_equal(b[i], 0xFF);
        }
    }
    const km_nor_sim_config_t bad_cell = {1024u, 3u, 2u, 0xFFu};
    const km_nor_sim_config_t too_big = {4096u, 8u, 4u, 0xFFu};
    assert_false(km_nor_sim_init(&s_sim, &bad_cell, &s_flash));
    assert_false(km_nor_sim_init(&s_sim, &too_big, &s_flash));
}

static void test_program_twice_is_refused_and_counted(void **state)
{
    (void)state;
    for (unsigned g = 0; g < sizeof s_geoms / sizeof s_geoms[0]; g++) {
        assert_true(km_nor_sim_init(&s_sim, &s_geoms[g], &s_flash));
        const uint32_t c = s_flash.prog_size;
        uint8_t a[8], b[8];
        prv_fill(a, c, 0x5A);
        assert_int_equal(s_flash.program(s_flash.ctx, c, a, c), KM_FLASH_OK);
        /* Even a program that would only clear more bits is refused. */
        prv_fill(b, c, 0x00);
        assert_int_equal(s_flash.program(s_flash.ctx, c, b, c), KM_FLASH_ERR_PROGRAM);
        assert_int_equal(s_sim.count.illegal, 1);
        assert_int_equal(s_flash.read(s_flash.ctx, c, b, c), KM_FLASH_OK);
        assert_memory_equal(a, b, c);
        /* A cell programmed with all ones is programmed too. */
        prv_fill(a, c, 0xFF);
        assert_int_equal(s_flash.program(s_flash.ctx, 2u * c, a, c), KM_FLASH_OK);
        assert_int_equal(s_flash.program(s_flash.ctx, 2u * c, a, c), KM_FLASH_ERR_PROGRAM);
        assert_int_equal(s_sim.count.illegal, 2);
        /* After an erase the cell takes a program again. */
        assert_int_equal(s_flash.erase(s_flash.ctx, 0), KM_FLASH_OK);
        prv_fill(a, c, 0x12);
        assert_int_equal(s_flash.program(s_flash.ctx, c, a, c), KM_FLASH_OK);
        assert_int_equal(s_sim.count.page_erases[0], 1);
        /* Every program call is counted, refused ones included. */
        assert_int_equal(s_sim.count.programs, 5);
        assert_int_equal(s_sim.count.erases, 1);
    }
}

static void test_alignment_and_range(void **state)
{
    (void)state;
    for (unsigned g = 0; g < sizeof s_geoms / sizeof s_geoms[0]; g++) {
        assert_true(km_nor_sim_init(&s_sim, &s_geoms[g], &s_flash));
        const uint32_t c = s_flash.prog_size;
        const uint32_t total = s_flash.page_size * s_flash.page_count;
        uint8_t a[16];
        prv_fill(a, sizeof a, 0);
        assert_int_equal(s_flash.program(s_flash.ctx, 1, a, c), KM_FLASH_ERR_ALIGN);
        assert_int_equal(s_flash.program(s_flash.ctx, 0, a, c - 1u), KM_FLASH_ERR_ALIGN);
        assert_int_equal(s_flash.program(s_flash.ctx, 0, a, 0), KM_FLASH_ERR_ALIGN);
        assert_int_equal(s_flash.program(s_flash.ctx, total, a, c), KM_FLASH_ERR_ALIGN);
        assert_int_equal(s_flash.erase(s_flash.ctx, s_flash.page_count), KM_FLASH_ERR_ALIGN);
        assert_int_equal(s_flash.read(s_flash.ctx, total - 1u, a, 2), KM_FLASH_ERR_ALIGN);
        assert_int_equal(s_sim.count.align_errors, 6);
        assert_int_equal(s_sim.count.programs, 0);
        /* Two cells in one call are fine. */
        assert_int_equal(s_flash.program(s_flash.ctx, 0, a, 2u * c), KM_FLASH_OK);
    }
}

static void test_erase_is_per_page(void **state)
{
    (void)state;
    assert_true(km_nor_sim_init(&s_sim, &s_geoms[1], &s_flash));
    uint8_t a[2] = {0x11, 0x22}, b[2];
    assert_int_equal(s_flash.program(s_flash.ctx, 1022, a, 2), KM_FLASH_OK); /* end of page 0 */
    assert_int_equal(s_flash.program(s_flash.ctx, 1024, a, 2), KM_FLASH_OK); /* start of page 1 */
    assert_int_equal(s_flash.erase(s_flash.ctx, 0), KM_FLASH_OK);
    assert_int_equal(s_flash.read(s_flash.ctx, 1022, b, 2), KM_FLASH_OK);
    assert_int_equal(b[0], 0xFF);
    assert_int_equal(s_flash.read(s_flash.ctx, 1024, b, 2), KM_FLASH_OK);
    assert_memory_equal(a, b, 2);
}

static void test_qemu_zero_fill_needs_erase(void **state)
{
    (void)state;
    const km_nor_sim_config_t q = {1024u, 4u, 2u, 0x00u};
    assert_true(km_nor_sim_init(&s_sim, &q, &s_flash));
    uint8_t a[4] = {1, 2, 3, 4}, b[4];
    assert_int_equal(s_flash.read(s_flash.ctx, 0, b, 4), KM_FLASH_OK);
    assert_int_equal(b[0], 0x00);
    assert_int_equal(s_flash.program(s_flash.ctx, 0, a, 4), KM_FLASH_ERR_PROGRAM);
    assert_int_equal(s_flash.erase(s_flash.ctx, 0), KM_FLASH_OK);
    assert_int_equal(s_flash.program(s_flash.ctx, 0, a, 4), KM_FLASH_OK);
}

/* Programs one cell with the cut armed on it and returns what reads show. */
static km_flash_result_t prv_cut_program(km_nor_prog_outcome_t o, const uint8_t *target, uint8_t *seen)
{
    assert_true(km_nor_sim_init(&s_sim, &s_geoms[0], &s_flash));
    km_nor_sim_seed(&s_sim, 1234u + (uint32_t)o);
    km_nor_sim_arm_cut(&s_sim, 0, o, KM_NOR_ERASE_NOT_DONE);
    assert_int_not_equal(s_flash.program(s_flash.ctx, 8, target, 8), KM_FLASH_OK);
    assert_true(km_nor_sim_cut_fired(&s_sim));
    /* Dead until power returns: nothing more happens. */
    assert_int_not_equal(s_flash.program(s_flash.ctx, 16, target, 8), KM_FLASH_OK);
    km_nor_sim_power_cycle(&s_sim);
    return s_flash.read(s_flash.ctx, 8, seen, 8);
}

static void test_cut_program_outcomes(void **state)
{
    (void)state;
    const uint8_t t[8] = {0x53, 0x01, 0x00, 0x00, 0x12, 0x34, 0x00, 0x80};
    const uint8_t ones[8] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};
    uint8_t seen[8];

    assert_int_equal(prv_cut_program(KM_NOR_PROG_NOT_DONE, t, seen), KM_FLASH_OK);
    assert_memory_equal(seen, ones, 8);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_OK);

    assert_int_equal(prv_cut_program(KM_NOR_PROG_DONE, t, seen), KM_FLASH_OK);
    assert_memory_equal(seen, t, 8);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_ERR_PROGRAM);

    /* All ones: passes the erased check, a new program lands. */
    assert_int_equal(prv_cut_program(KM_NOR_PROG_TORN_ONES, t, seen), KM_FLASH_OK);
    assert_memory_equal(seen, ones, 8);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_OK);
    assert_int_equal(s_flash.read(s_flash.ctx, 8, seen, 8), KM_FLASH_OK);
    assert_memory_equal(seen, t, 8);

    /* Mixed: neither target nor erased, only bits the target clears are
     * cleared, and it cannot be programmed again. */
    assert_int_equal(prv_cut_program(KM_NOR_PROG_TORN_MIXED, t, seen), KM_FLASH_OK);
    assert_memory_not_equal(seen, t, 8);
    assert_memory_not_equal(seen, ones, 8);
    for (unsigned i = 0; i < 8; i++) {
        assert_int_equal(seen[i] & t[i], t[i]);
    }
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_ERR_PROGRAM);

    /* Unstable: over many reads both the target and a mix show up. */
    assert_int_equal(prv_cut_program(KM_NOR_PROG_TORN_UNSTABLE, t, seen), KM_FLASH_OK);
    unsigned as_target = 0, as_mix = 0;
    for (unsigned r = 0; r < 64; r++) {
        assert_int_equal(s_flash.read(s_flash.ctx, 8, seen, 8), KM_FLASH_OK);
        if (memcmp(seen, t, 8) == 0) {
            as_target++;
        } else {
            assert_memory_not_equal(seen, ones, 8);
            as_mix++;
        }
    }
    assert_true(as_target > 0 && as_mix > 0);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_ERR_PROGRAM);

    assert_int_equal(prv_cut_program(KM_NOR_PROG_TORN_ECC, t, seen), KM_FLASH_ERR_ECC);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_ERR_PROGRAM);
    /* The erase heals every torn state. */
    assert_int_equal(s_flash.erase(s_flash.ctx, 0), KM_FLASH_OK);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_OK);
}

static void test_cut_counts_ops_across_program_and_erase(void **state)
{
    (void)state;
    assert_true(km_nor_sim_init(&s_sim, &s_geoms[0], &s_flash));
    uint8_t a[8] = {0};
    km_nor_sim_arm_cut(&s_sim, 2, KM_NOR_PROG_DONE, KM_NOR_ERASE_NOT_DONE);
    assert_int_equal(s_flash.program(s_flash.ctx, 0, a, 8), KM_FLASH_OK);
    assert_int_equal(s_flash.erase(s_flash.ctx, 1), KM_FLASH_OK);
    assert_false(km_nor_sim_cut_fired(&s_sim));
    assert_int_not_equal(s_flash.erase(s_flash.ctx, 1), KM_FLASH_OK);
    assert_true(km_nor_sim_cut_fired(&s_sim));
    assert_true(s_sim.cut_was_erase);
    assert_int_equal(km_nor_sim_ops(&s_sim), 3);
}

/* Fills page 0 with a pattern, cuts its erase with outcome o. */
static void prv_cut_erase(km_nor_erase_outcome_t o, unsigned *erased, unsigned *old, unsigned *other,
                          unsigned *ecc)
{
    assert_true(km_nor_sim_init(&s_sim, &s_geoms[1], &s_flash));
    km_nor_sim_seed(&s_sim, 99u + (uint32_t)o);
    const uint8_t pat[2] = {0x0F, 0x30};
    for (uint32_t off = 0; off < 1024u; off += 2u) {
        assert_int_equal(s_flash.program(s_flash.ctx, off, pat, 2), KM_FLASH_OK);
    }
    km_nor_sim_arm_cut(&s_sim, km_nor_sim_ops(&s_sim), KM_NOR_PROG_DONE, o);
    assert_int_not_equal(s_flash.erase(s_flash.ctx, 0), KM_FLASH_OK);
    km_nor_sim_power_cycle(&s_sim);
    *erased = *old = *other = *ecc = 0;
    for (uint32_t off = 0; off < 1024u; off += 2u) {
        uint8_t b[2];
        const km_flash_result_t r = s_flash.read(s_flash.ctx, off, b, 2);
        if (r == KM_FLASH_ERR_ECC) {
            (*ecc)++;
        } else if (b[0] == 0xFF && b[1] == 0xFF) {
            (*erased)++;
        } else if (memcmp(b, pat, 2) == 0) {
            (*old)++;
        } else {
            /* Erase only sets bits. */
            assert_int_equal(b[0] & pat[0], pat[0]);
            assert_int_equal(b[1] & pat[1], pat[1]);
            (*other)++;
        }
    }
}

static void test_cut_erase_outcomes(void **state)
{
    (void)state;
    unsigned erased, old, other, ecc;
    prv_cut_erase(KM_NOR_ERASE_NOT_DONE, &erased, &old, &other, &ecc);
    assert_int_equal(old, 512);
    prv_cut_erase(KM_NOR_ERASE_DONE, &erased, &old, &other, &ecc);
    assert_int_equal(erased, 512);
    prv_cut_erase(KM_NOR_ERASE_HALF, &erased, &old, &other, &ecc);
    assert_int_equal(erased, 256);
    assert_int_equal(old, 256);
    prv_cut_erase(KM_NOR_ERASE_GARBAGE, &erased, &old, &other, &ecc);
    assert_true(other > 0 && ecc > 0);
    assert_int_equal(old + other + ecc + erased, 512);
    prv_cut_erase(KM_NOR_ERASE_MIXED, &erased, &old, &other, &ecc);
    assert_true(erased > 0 && old > 0 && other > 0);
    /* Garbage cells are not erased: programming them is refused. */
    for (uint32_t off = 0; off < 1024u; off += 2u) {
        uint8_t b[2];
        if (s_flash.read(s_flash.ctx, off, b, 2) == KM_FLASH_OK && b[0] != 0xFF) {
            const uint8_t z[2] = {0, 0};
            assert_int_equal(s_flash.program(s_flash.ctx, off, z, 2), KM_FLASH_ERR_PROGRAM);
            break;
        }
    }
}

static const uint8_t k_ones[8] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF};

/* (a) A program cut weak: each read shows the erased side, the target or
 * bits in between, chosen by the seeded PRNG; a read policy pins it. */
static void test_weak_program_reads_vary(void **state)
{
    (void)state;
    const uint8_t t[8] = {0x53, 0x01, 0x00, 0x00, 0x12, 0x34, 0x00, 0x80};
    uint8_t seen[8];
    assert_int_equal(prv_cut_program(KM_NOR_PROG_TORN_WEAK, t, seen), KM_FLASH_OK);
    unsigned erased = 0, target = 0, between = 0;
    for (unsigned r = 0; r < 256; r++) {
        assert_int_equal(s_flash.read(s_flash.ctx, 8, seen, 8), KM_FLASH_OK);
        for (unsigned i = 0; i < 8; i++) {
            assert_int_equal(seen[i] & t[i], t[i]); /* only bits the target clears */
        }
        if (memcmp(seen, k_ones, 8) == 0) {
            erased++;
        } else if (memcmp(seen, t, 8) == 0) {
            target++;
        } else {
            between++;
        }
    }
    assert_true(erased > 0 && target > 0 && between > 0);
    /* The same seed gives the same reads. */
    km_nor_sim_t copy = s_sim;
    uint8_t a[8], b[8];
    assert_int_equal(s_flash.read(s_flash.ctx, 8, a, 8), KM_FLASH_OK);
    s_sim = copy;
    assert_int_equal(s_flash.read(s_flash.ctx, 8, b, 8), KM_FLASH_OK);
    assert_memory_equal(a, b, 8);
    km_nor_sim_set_weak_reads(&s_sim, KM_NOR_WEAK_HIGH);
    assert_int_equal(s_flash.read(s_flash.ctx, 8, seen, 8), KM_FLASH_OK);
    assert_memory_equal(seen, k_ones, 8);
    km_nor_sim_set_weak_reads(&s_sim, KM_NOR_WEAK_LOW);
    assert_int_equal(s_flash.read(s_flash.ctx, 8, seen, 8), KM_FLASH_OK);
    assert_memory_equal(seen, t, 8);
    /* Not erased: the ideal check refuses a new program, and it counts. */
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_ERR_PROGRAM);
    assert_int_equal(s_sim.count.illegal, 1);
    assert_int_equal(s_sim.count.violations, 1);
    assert_int_equal(s_flash.erase(s_flash.ctx, 0), KM_FLASH_OK);
    km_nor_sim_set_weak_reads(&s_sim, KM_NOR_WEAK_LOW);
    assert_int_equal(s_flash.read(s_flash.ctx, 8, seen, 8), KM_FLASH_OK);
    assert_memory_equal(seen, k_ones, 8);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_OK);
    assert_int_equal(s_sim.count.violations, 1);
}

/* Content check: a weak cell that reads erased passes the controller's
 * check, the program lands on it (a violation) and the cell stays weak
 * where the old one was: it may read the new value now and not later. */
static void test_content_check_lets_a_weak_cell_through(void **state)
{
    (void)state;
    const uint8_t t[8] = {0x44, 0x01, 0x00, 0x00, 0x12, 0x34, 0x56, 0x78};
    const uint8_t n[8] = {0x44, 0x02, 0x00, 0x00, 0x0F, 0x00, 0x00, 0x00};
    uint8_t seen[8];
    assert_int_equal(prv_cut_program(KM_NOR_PROG_TORN_WEAK, t, seen), KM_FLASH_OK);
    const km_nor_sim_rules_t rules = {.ecc_dword = false, .content_check = true};
    km_nor_sim_set_rules(&s_sim, &rules);
    km_nor_sim_set_weak_reads(&s_sim, KM_NOR_WEAK_LOW);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, n, 8), KM_FLASH_ERR_PROGRAM);
    assert_int_equal(s_sim.count.illegal, 1);
    km_nor_sim_set_weak_reads(&s_sim, KM_NOR_WEAK_HIGH);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, n, 8), KM_FLASH_OK);
    assert_int_equal(s_sim.count.illegal, 1);
    assert_int_equal(s_sim.count.violations, 2);
    assert_int_equal(s_flash.read(s_flash.ctx, 8, seen, 8), KM_FLASH_OK);
    assert_memory_equal(seen, n, 8);
    km_nor_sim_set_weak_reads(&s_sim, KM_NOR_WEAK_LOW);
    assert_int_equal(s_flash.read(s_flash.ctx, 8, seen, 8), KM_FLASH_OK);
    for (unsigned i = 0; i < 8; i++) {
        assert_int_equal(seen[i], n[i] & t[i]);
    }
    /* A clean program is no violation; a programmed cell fails the check. */
    assert_int_equal(s_flash.program(s_flash.ctx, 16, n, 8), KM_FLASH_OK);
    assert_int_equal(s_flash.program(s_flash.ctx, 16, n, 8), KM_FLASH_ERR_PROGRAM);
    assert_int_equal(s_sim.count.illegal, 2);
    assert_int_equal(s_sim.count.violations, 3);
}

/* (c) STM32G0: a double word whose program was started has part of its ECC
 * written; even reading all 0xFF it must not be programmed again. */
static void test_ecc_dword_started_program_is_final(void **state)
{
    (void)state;
    const uint8_t t[8] = {0x53, 0x01, 0x00, 0x00, 0x12, 0x34, 0x00, 0x80};
    uint8_t seen[8];
    /* Without the rule (F0, nRF51): the cell that no bit moved in takes the
     * program, but it is still a violation of "never program a touched cell". */
    assert_int_equal(prv_cut_program(KM_NOR_PROG_TORN_ONES, t, seen), KM_FLASH_OK);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_OK);
    assert_int_equal(s_sim.count.illegal, 0);
    assert_int_equal(s_sim.count.violations, 1);
    /* With it, the ideal check refuses... */
    const km_nor_sim_rules_t ecc = {.ecc_dword = true, .content_check = false};
    assert_int_equal(prv_cut_program(KM_NOR_PROG_TORN_ONES, t, seen), KM_FLASH_OK);
    km_nor_sim_set_rules(&s_sim, &ecc);
    assert_memory_equal(seen, k_ones, 8);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_ERR_PROGRAM);
    assert_int_equal(s_sim.count.illegal, 1);
    assert_int_equal(s_sim.count.violations, 1);
    /* ...and a check that reads content lets it through, after which the
     * double word reads with an ECC error. */
    const km_nor_sim_rules_t g0 = {.ecc_dword = true, .content_check = true};
    assert_int_equal(prv_cut_program(KM_NOR_PROG_TORN_ONES, t, seen), KM_FLASH_OK);
    km_nor_sim_set_rules(&s_sim, &g0);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_OK);
    assert_int_equal(s_sim.count.illegal, 0);
    assert_int_equal(s_sim.count.violations, 1);
    assert_int_equal(s_flash.read(s_flash.ctx, 8, seen, 8), KM_FLASH_ERR_ECC);
    /* Same for a weak cell read as erased. */
    assert_int_equal(prv_cut_program(KM_NOR_PROG_TORN_WEAK, t, seen), KM_FLASH_OK);
    km_nor_sim_set_rules(&s_sim, &g0);
    km_nor_sim_set_weak_reads(&s_sim, KM_NOR_WEAK_HIGH);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_OK);
    assert_int_equal(s_sim.count.violations, 1);
    assert_int_equal(s_flash.read(s_flash.ctx, 8, seen, 8), KM_FLASH_ERR_ECC);
    /* An erase makes it programmable again. */
    assert_int_equal(s_flash.erase(s_flash.ctx, 0), KM_FLASH_OK);
    assert_int_equal(s_flash.program(s_flash.ctx, 8, t, 8), KM_FLASH_OK);
    assert_int_equal(s_flash.read(s_flash.ctx, 8, seen, 8), KM_FLASH_OK);
    assert_memory_equal(seen, t, 8);
    assert_int_equal(s_sim.count.violations, 1);
}

/* (b) An erase cut weak: every written cell reads its old content, erased,
 * or between, differently from one read to the next; a whole page can read
 * erased once and not the next time. Programming such a cell is a violation. */
static void test_weak_erase_reads_vary(void **state)
{
    (void)state;
    unsigned erased, old, other, ecc;
    prv_cut_erase(KM_NOR_ERASE_WEAK, &erased, &old, &other, &ecc);
    assert_true(erased > 0 && old > 0 && other > 0);
    assert_int_equal(ecc, 0);
    assert_int_equal(erased + old + other, 512);
    uint8_t page[1024];
    km_nor_sim_set_weak_reads(&s_sim, KM_NOR_WEAK_HIGH);
    assert_int_equal(s_flash.read(s_flash.ctx, 0, page, sizeof page), KM_FLASH_OK);
    for (unsigned i = 0; i < sizeof page; i++) {
        assert_int_equal(page[i], 0xFF);
    }
    km_nor_sim_set_weak_reads(&s_sim, KM_NOR_WEAK_LOW);
    assert_int_equal(s_flash.read(s_flash.ctx, 0, page, sizeof page), KM_FLASH_OK);
    assert_int_equal(page[0], 0x0F);
    assert_int_equal(page[1023], 0x30);
    const uint8_t z[2] = {0x00, 0x00};
    assert_int_equal(s_flash.program(s_flash.ctx, 0, z, 2), KM_FLASH_ERR_PROGRAM);
    const km_nor_sim_rules_t content = {.ecc_dword = false, .content_check = true};
    km_nor_sim_set_rules(&s_sim, &content);
    km_nor_sim_set_weak_reads(&s_sim, KM_NOR_WEAK_HIGH);
    assert_int_equal(s_flash.program(s_flash.ctx, 2, z, 2), KM_FLASH_OK);
    assert_int_equal(s_sim.count.violations, 2);
    /* Page 1 was never written: a weak erase of page 0 leaves it alone, and
     * a complete erase heals page 0. */
    assert_int_equal(s_flash.erase(s_flash.ctx, 0), KM_FLASH_OK);
    km_nor_sim_set_weak_reads(&s_sim, KM_NOR_WEAK_LOW);
    assert_int_equal(s_flash.read(s_flash.ctx, 0, page, sizeof page), KM_FLASH_OK);
    for (unsigned i = 0; i < sizeof page; i++) {
        assert_int_equal(page[i], 0xFF);
    }
    assert_int_equal(s_flash.program(s_flash.ctx, 0, z, 2), KM_FLASH_OK);
    assert_int_equal(s_sim.count.violations, 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_geometry_and_erased_start),
        cmocka_unit_test(test_program_twice_is_refused_and_counted),
        cmocka_unit_test(test_alignment_and_range),
        cmocka_unit_test(test_erase_is_per_page),
        cmocka_unit_test(test_qemu_zero_fill_needs_erase),
        cmocka_unit_test(test_cut_program_outcomes),
        cmocka_unit_test(test_cut_counts_ops_across_program_and_erase),
        cmocka_unit_test(test_cut_erase_outcomes),
        cmocka_unit_test(test_weak_program_reads_vary),
        cmocka_unit_test(test_content_check_lets_a_weak_cell_through),
        cmocka_unit_test(test_ecc_dword_started_program_is_final),
        cmocka_unit_test(test_weak_erase_reads_vary),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
