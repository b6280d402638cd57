/* SPDX-License-Identifier: Apache-2.0 */
/* What the bootloader answers in update mode (docs/update.md §3, §4;
 * firmware/update/km_boot_serve.c): ping, reads of 0x01 and 0x0C, the
 * standard restart, 0x78 through the state machine, bit 5 for everything
 * else (docs/protocol.md §4), its own ID and broadcast only. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_boot_serve.h"
#include "km_test_support.h"
#include "km_update_rig.h"

static rig_t s_r;
static km_boot_serve_t s_s;
static km_boot_reply_t s_rep;
static km_boot_shared_t s_sh; /* the words shared with the application */

static int prv_setup(void **state)
{
    (void)state;
    rig_init(&s_r, 1024u, 4u, 8u, 6u, 0xFFu);
    memset(&s_s, 0, sizeof s_s);
    km_update_init(&s_s.upd, &s_r.region, &s_r.target);
    s_s.id = 7u;
    s_s.version = 0x10100100u;
    memset(&s_sh, 0, sizeof s_sh);
    s_s.shared = &s_sh;
    return 0;
}

/* Runs one frame given as hex (header to checksum, as on the wire). */
static void prv_frame(const char *hex)
{
    uint8_t b[300];
    const unsigned n = kt_hex(hex, b, sizeof b);
    assert_true(n >= 6u);
    const km_frame_view_t v = {b[2], b[4], (uint8_t)(b[3] - 2u), &b[5], 0u};
    km_boot_serve(&s_s, &v, &s_rep);
}

static void prv_answer_is(const char *hex)
{
    uint8_t want[300];
    const unsigned n = kt_hex(hex, want, sizeof want);
    assert_int_equal(s_rep.len, n);
    assert_memory_equal(s_rep.bytes, want, n);
}

/* §3: ping and 0x0C on its own ID; broadcast runs but is never answered;
 * another ID is ignored. */
static void test_ping_and_version(void **state)
{
    (void)state;
    prv_frame("F9 FF 07 02 01 F5");
    prv_answer_is("F9 F5 07 02 00 F6");
    prv_frame("F9 FF 07 03 02 0C E7");
    prv_answer_is("F9 F5 07 07 02 0C 00 01 10 10 C2");
    prv_frame("F9 FF FE 02 01 FE");
    prv_answer_is("");
    prv_frame("F9 FF 01 02 01 FB");
    prv_answer_is("");
}

/* §4: an unknown command, an unreadable address, a write that is not the
 * restart: bit 5, told by the next status answer, then cleared. */
static void test_bit5_life_cycle(void **state)
{
    (void)state;
    prv_frame("F9 FF 07 04 03 0F 00 E2"); /* a write: nothing is writable here */
    prv_answer_is("");
    prv_frame("F9 FF 07 02 01 F5");
    prv_answer_is("F9 F5 07 02 20 D6");
    prv_frame("F9 FF 07 02 01 F5");
    prv_answer_is("F9 F5 07 02 00 F6");
    prv_frame("F9 FF 07 03 02 46 AD"); /* read of 0x46: not here */
    prv_answer_is("F9 F5 07 02 20 D6");
    prv_frame("F9 FF 07 02 83 73"); /* 0x83 */
    prv_answer_is("");
    prv_frame("F9 FF 07 03 02 01 F2"); /* status register carries it */
    prv_answer_is("F9 F5 07 05 02 01 20 00 D0");
}

/* The standard restart, to its ID or broadcast: the restart action, no
 * answer; a wrong magic is not a restart. */
static void test_restart(void **state)
{
    (void)state;
    prv_frame("F9 FF 07 07 03 02 E1 E2 E3 E4 62");
    assert_int_equal(s_rep.action, KM_BOOT_ACT_RESTART);
    prv_answer_is("");
    prv_frame("F9 FF FE 07 03 02 E1 E2 E3 E4 6B");
    assert_int_equal(s_rep.action, KM_BOOT_ACT_RESTART);
    prv_frame("F9 FF 07 07 03 02 E1 E2 E3 E5 61");
    assert_int_equal(s_rep.action, KM_BOOT_ACT_NONE);
}

/* §4: 0x78 through the state machine: STATUS answered to its ID, START is
 * the restart, an unknown sub is bit 5 with the short response. */
static void test_update_frames(void **state)
{
    (void)state;
    prv_frame("F9 FF 07 05 78 04 00 00 77");
    prv_answer_is("F9 F5 07 0B 78 04 01 00 00 00 00 00 00 00 70");
    prv_frame("F9 FF FE 05 78 04 00 00 80");
    prv_answer_is("");
    prv_frame("F9 FF 07 07 78 07 E1 E2 E3 E4 E8");
    assert_int_equal(s_rep.action, KM_BOOT_ACT_RESTART);
    prv_frame("F9 FF 07 03 78 09 74");
    prv_answer_is("F9 F5 07 02 20 D6");
}

/* §3a: an image that used up its tries (the bootloader stays in update
 * mode) gets new ones from START, not from the standard restart, nor
 * from anything else the bootloader answers. */
static void test_start_gives_new_tries(void **state)
{
    (void)state;
    for (uint32_t i = 0; i < KM_BOOT_TRIAL_MAX; i++) {
        assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
    }
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_STAY_GAVE_UP);
    prv_frame("F9 FF 07 02 01 F5");                /* ping */
    prv_frame("F9 FF 07 05 78 04 00 00 77");       /* STATUS */
    prv_frame("F9 FF 07 07 78 01 B1 B2 B3 B4 AE"); /* ENTER: ends a session */
    prv_frame("F9 FF 07 07 78 07 E1 E2 E3 E5 E7"); /* START, bad magic */
    prv_frame("F9 FF FE 07 03 02 E1 E2 E3 E4 6B"); /* the standard restart */
    assert_int_equal(s_rep.action, KM_BOOT_ACT_RESTART);
    assert_int_equal(km_boot_attempts(&s_sh), KM_BOOT_TRIAL_MAX);
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_STAY_GAVE_UP);
    prv_frame("F9 FF FE 07 78 07 E1 E2 E3 E4 F1"); /* START, broadcast */
    assert_int_equal(s_rep.action, KM_BOOT_ACT_RESTART);
    assert_int_equal(km_boot_attempts(&s_sh), 0);
    assert_int_equal(km_boot_decide(&s_sh, true), KM_BOOT_RUN);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_ping_and_version, prv_setup),
        cmocka_unit_test_setup(test_bit5_life_cycle, prv_setup),
        cmocka_unit_test_setup(test_restart, prv_setup),
        cmocka_unit_test_setup(test_update_frames, prv_setup),
        cmocka_unit_test_setup(test_start_gives_new_tries, prv_setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
