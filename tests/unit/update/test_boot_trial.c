/* SPDX-License-Identifier: Apache-2.0 */
/* The trial of an image (docs/update.md §3a, firmware/update/km_boot_trial.c)
 * and the entry check (§3, km_boot_entry in km_boot_check.c): the
 * bootloader's decision over the words it shares with the application, at
 * every reset; and the initial SP and reset vector it requires before a
 * jump. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "km_boot_check.h"
#include "km_boot_trial.h"
#include "km_update_rig.h"

static km_boot_shared_t s_sh;

/* Every test starts from all-zero words. */
static int prv_setup(void **state)
{
    (void)state;
    memset(&s_sh, 0, sizeof s_sh);
    return 0;
}

/* Fills the words with xorshift garbage, as RAM reads after power-on. */
static void prv_garbage(uint32_t seed)
{
    uint32_t x = seed | 1u;
    uint32_t *w = (uint32_t *)(void *)&s_sh;
    for (size_t i = 0; i < sizeof s_sh / 4u; i++) {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        w[i] = x;
    }
}

/* §3a: power-on garbage reads as no attempts (the check word): 100,000
 * random fills, all-zero and all-ones RAM each start the image, counted
 * once. */
static void test_power_on_garbage_is_zero_attempts(void **state)
{
    (void)state;
    for (uint32_t seed = 1; seed <= 100000u; seed++) {
        prv_garbage(seed * 2654435761u);
        s_sh.request = 0u; /* garbage that is exactly the request magic: below */
        assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
        assert_int_equal(km_boot_attempts(&s_sh), 1);
    }
    memset(&s_sh, 0x00, sizeof s_sh);
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
    assert_int_equal(km_boot_attempts(&s_sh), 1);
    memset(&s_sh, 0xFF, sizeof s_sh);
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
    assert_int_equal(km_boot_attempts(&s_sh), 1);
}

/* §3a: a count whose check word is wrong, or above the maximum with a
 * right one, is not a count. */
static void test_count_needs_its_check_word(void **state)
{
    (void)state;
    s_sh.attempts = KM_BOOT_TRIAL_MAX;
    s_sh.attempts_check = KM_BOOT_TRIAL_MAX ^ KM_BOOT_TRIAL_KEY ^ 1u;
    assert_int_equal(km_boot_attempts(&s_sh), 0);
    s_sh.attempts = KM_BOOT_TRIAL_MAX + 1u;
    s_sh.attempts_check = (KM_BOOT_TRIAL_MAX + 1u) ^ KM_BOOT_TRIAL_KEY;
    assert_int_equal(km_boot_attempts(&s_sh), 0);
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
    s_sh.attempts = 2u;
    s_sh.attempts_check = 2u ^ KM_BOOT_TRIAL_KEY;
    assert_int_equal(km_boot_attempts(&s_sh), 2);
}

/* §3a: an image that never confirms is started KM_BOOT_TRIAL_MAX times,
 * then the bootloader stays in update mode at every further reset. */
static void test_unconfirmed_starts_give_up(void **state)
{
    (void)state;
    for (uint32_t i = 1; i <= KM_BOOT_TRIAL_MAX; i++) {
        s_sh.app_running = KM_BOOT_APP_MAGIC; /* what the jump leaves */
        assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
        assert_int_equal(km_boot_attempts(&s_sh), i);
        assert_int_equal(s_sh.app_running, 0);
    }
    for (int i = 0; i < 5; i++) {
        assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_STAY_GAVE_UP);
        assert_int_equal(km_boot_attempts(&s_sh), KM_BOOT_TRIAL_MAX);
    }
}

/* §3a: a confirmed start that later resets (restart, watchdog, fault)
 * boots normally again, however often; the count starts over each time. */
static void test_confirmed_start_boots_again(void **state)
{
    (void)state;
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN); /* one failed start */
    for (int i = 0; i < 20; i++) {
        km_boot_confirm(&s_sh);
        assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
        assert_int_equal(km_boot_attempts(&s_sh), 1);
        assert_int_equal(s_sh.confirmed, 0); /* consumed: each start confirms again */
    }
    /* Confirmed on the last try: still a new trial. */
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
    assert_int_equal(km_boot_attempts(&s_sh), KM_BOOT_TRIAL_MAX);
    km_boot_confirm(&s_sh);
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
}

/* §3: the ENTER request wins over a runnable image and is consumed; the
 * next reset starts the image (its count unchanged by the visit). */
static void test_enter_request(void **state)
{
    (void)state;
    km_boot_confirm(&s_sh);
    s_sh.request = KM_BOOT_REQUEST_MAGIC;
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_STAY_ASKED);
    assert_int_equal(s_sh.request, 0);
    assert_int_equal(km_boot_attempts(&s_sh), 0);
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
    /* An image that used up its tries: ENTER, then still update mode. */
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
    s_sh.request = KM_BOOT_REQUEST_MAGIC;
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_STAY_ASKED);
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_STAY_GAVE_UP);
}

/* §3: no image to start: update mode, whatever the words say; the
 * request and the confirmation are consumed all the same. */
static void test_no_image(void **state)
{
    (void)state;
    km_boot_confirm(&s_sh);
    s_sh.request = KM_BOOT_REQUEST_MAGIC;
    assert_int_equal(km_boot_decide(&s_sh, false), KM_BOOT_STAY_NO_IMAGE);
    assert_int_equal(s_sh.request, 0);
    assert_int_equal(s_sh.confirmed, 0);
    assert_int_equal(km_boot_decide(&s_sh, false), KM_BOOT_STAY_NO_IMAGE);
    assert_int_equal(km_boot_attempts(&s_sh), 0);
}

/* §3a: COMMIT and START give an image that gave up new tries. */
static void test_fresh_trial(void **state)
{
    (void)state;
    for (uint32_t i = 0; i < KM_BOOT_TRIAL_MAX; i++) {
        (void)km_boot_decide(&s_sh, true);
    }
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_STAY_GAVE_UP);
    km_boot_trial_fresh(&s_sh);
    for (uint32_t i = 0; i < KM_BOOT_TRIAL_MAX; i++) {
        assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
    }
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_STAY_GAVE_UP);
}

/* The application's side: started by a bootloader only if the version
 * words agree. */
static void test_started_by_loader(void **state)
{
    (void)state;
    assert_false(km_boot_started_by_loader(&s_sh));
    s_sh.boot_version = 0x10u;
    s_sh.check = ~0x10u;
    assert_true(km_boot_started_by_loader(&s_sh));
    s_sh.check ^= 0x100u;
    assert_false(km_boot_started_by_loader(&s_sh));
}

/* ---- the entry check (§3) ---------------------------------------------- */

#define PRV_RAM_LO 0x20000000u
#define PRV_RAM_HI 0x20001FE0u

static rig_t s_r;
static km_image_header_t s_h;

/* An image header of `length` bytes and its vector table's first two
 * words, programmed into a fresh region. */
static void prv_table(uint32_t length, uint32_t sp, uint32_t pc)
{
    rig_init(&s_r, 2048u, 8u, 4u, 2u, 0xFFu);
    s_h = (km_image_header_t){.magic = KM_IMAGE_MAGIC,
                              .model = KM_MODEL_STM32G031,
                              .length = length,
                              .vectors = KM_IMAGE_VECTORS,
                              .base = RIG_BASE};
    uint8_t w[8];
    rig_put32(w, sp);
    rig_put32(w + 4, pc);
    assert_int_equal(s_r.region.program(s_r.region.ctx, KM_IMAGE_VECTORS, w, 8u), KM_FLASH_OK);
}

/* The entry check of the table prv_table wrote. */
static bool prv_entry(void)
{
    km_boot_entry_t e;
    const bool ok = km_boot_entry(&s_r.region, &s_h, PRV_RAM_LO, PRV_RAM_HI, &e);
    return ok;
}

/* A sound table: SP and PC as read. */
static void test_entry_sound(void **state)
{
    (void)state;
    prv_table(0x600u, PRV_RAM_HI, RIG_BASE + 0x1C1u);
    km_boot_entry_t e;
    assert_true(km_boot_entry(&s_r.region, &s_h, PRV_RAM_LO, PRV_RAM_HI, &e));
    assert_int_equal(e.sp, PRV_RAM_HI);
    assert_int_equal(e.pc, RIG_BASE + 0x1C1u);
}

/* The reset vector inside the image, not merely inside the region: the
 * region is 4 KiB here, the image 0x600 bytes (issue 18 item 5). */
static void test_entry_reset_vector_inside_the_image(void **state)
{
    (void)state;
    prv_table(0x600u, PRV_RAM_HI, RIG_BASE + 0x600u - 2u + 1u); /* last halfword */
    assert_true(prv_entry());
    prv_table(0x600u, PRV_RAM_HI, RIG_BASE + 0x600u + 1u); /* the first byte after it */
    assert_false(prv_entry());
    prv_table(0x600u, PRV_RAM_HI, RIG_BASE + 0x800u + 1u); /* region, not image */
    assert_false(prv_entry());
    prv_table(0x600u, PRV_RAM_HI, RIG_BASE + 0x600u - 1u + 1u); /* straddles the end */
    assert_false(prv_entry());
    prv_table(0x600u, PRV_RAM_HI, RIG_BASE + KM_IMAGE_VECTORS + 1u); /* the table's start */
    assert_true(prv_entry());
    prv_table(0x600u, PRV_RAM_HI, RIG_BASE + 0x41u); /* in the header */
    assert_false(prv_entry());
    prv_table(0x600u, PRV_RAM_HI, 0x00000001u); /* below the region */
    assert_false(prv_entry());
    prv_table(0x600u, PRV_RAM_HI, 0xFFFFFFFFu);
    assert_false(prv_entry());
}

/* Thumb only: bit 0 clear would fault at once on a Cortex-M. */
static void test_entry_thumb_bit(void **state)
{
    (void)state;
    prv_table(0x600u, PRV_RAM_HI, RIG_BASE + 0x1C0u);
    assert_false(prv_entry());
}

/* The initial SP in [RAM start, the shared words]. */
static void test_entry_stack_pointer(void **state)
{
    (void)state;
    prv_table(0x600u, PRV_RAM_LO, RIG_BASE + 0x1C1u);
    assert_true(prv_entry());
    prv_table(0x600u, PRV_RAM_LO - 4u, RIG_BASE + 0x1C1u);
    assert_false(prv_entry());
    prv_table(0x600u, PRV_RAM_HI + 4u, RIG_BASE + 0x1C1u); /* would overwrite the shared words */
    assert_false(prv_entry());
    prv_table(0x600u, 0xFFFFFFFFu, RIG_BASE + 0x1C1u); /* erased */
    assert_false(prv_entry());
}

/* A read error is "do not start": the table's cell torn by a power cut
 * (an uncorrectable ECC error on the G0), or a table beyond the region. */
static void test_entry_read_error(void **state)
{
    (void)state;
    rig_init(&s_r, 2048u, 8u, 4u, 2u, 0xFFu);
    s_h = (km_image_header_t){.magic = KM_IMAGE_MAGIC,
                              .model = KM_MODEL_STM32G031,
                              .length = 0x600u,
                              .vectors = KM_IMAGE_VECTORS,
                              .base = RIG_BASE};
    uint8_t w[8];
    rig_put32(w, PRV_RAM_HI);
    rig_put32(w + 4, RIG_BASE + 0x1C1u);
    km_nor_sim_arm_cut(&s_r.sim, 0u, KM_NOR_PROG_TORN_ECC, KM_NOR_ERASE_NOT_DONE);
    (void)s_r.region.program(s_r.region.ctx, KM_IMAGE_VECTORS, w, 8u);
    assert_true(km_nor_sim_cut_fired(&s_r.sim));
    km_nor_sim_power_cycle(&s_r.sim);
    assert_false(prv_entry());
    prv_table(0x600u, PRV_RAM_HI, RIG_BASE + 0x1C1u);
    s_h.vectors = 4096u - 4u; /* the PC word lies beyond the 4 KiB region */
    assert_false(prv_entry());
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_power_on_garbage_is_zero_attempts, prv_setup),
        cmocka_unit_test_setup(test_count_needs_its_check_word, prv_setup),
        cmocka_unit_test_setup(test_unconfirmed_starts_give_up, prv_setup),
        cmocka_unit_test_setup(test_confirmed_start_boots_again, prv_setup),
        cmocka_unit_test_setup(test_enter_request, prv_setup),
        cmocka_unit_test_setup(test_no_image, prv_setup),
        cmocka_unit_test_setup(test_fresh_trial, prv_setup),
        cmocka_unit_test_setup(test_started_by_loader, prv_setup),
        cmocka_unit_test(test_entry_sound),
        cmocka_unit_test(test_entry_reset_vector_inside_the_image),
        cmocka_unit_test(test_entry_thumb_bit),
        cmocka_unit_test(test_entry_stack_pointer),
        cmocka_unit_test(test_entry_read_error),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
