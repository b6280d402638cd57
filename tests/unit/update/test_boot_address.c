/* SPDX-License-Identifier: Apache-2.0 */
/* Where the bootloader's update mode answers (docs/update.md §3,
 * firmware/update/km_boot_address.c): at the ID and baud the application
 * handed over with 0x78 ENTER (km_boot_handoff_set, one packed word with a
 * check byte in the shared RAM); without that, with the store reader at
 * the stored ID and baud (ID 0, 115200 on a blank store), and without the
 * store reader (the 32 KiB STM32G031F6's bootloader) at ID 1, 115200. A
 * word the application did not leave (power-on garbage) is not believed. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "km_boot_address.h"
#include "km_nor_sim.h"
#include "km_store.h"

#define PRV_SCHEMA 1u

static km_boot_shared_t s_sh;
static km_nor_sim_t s_sim;
static km_flash_t s_flash;

/* All-zero shared words and a blank STM32G0 store. */
static int prv_setup(void **state)
{
    (void)state;
    memset(&s_sh, 0, sizeof s_sh);
    static const km_nor_sim_config_t k_g0 = {2048u, 8u, 3u, 0xFFu};
    assert_true(km_nor_sim_init(&s_sim, &k_g0, &s_flash));
    return 0;
}

/* Saves ID and baud / 100 in the store as the application's schema would. */
static void prv_store(uint32_t id, uint32_t baud)
{
    static const km_store_key_t k_keys[] = {{0x0Fu, 0u}, {0x10u, 1152u}};
    static const km_store_schema_t k_schema = {k_keys, 2u, PRV_SCHEMA};
    km_store_t st;
    (void)km_store_mount(&st, &s_flash, &k_schema, NULL);
    static const uint8_t k_ids[2] = {0x0Fu, 0x10u};
    const uint32_t v[2] = {id, baud / 100u};
    assert_int_equal(km_store_commit(&st, k_ids, v, 2u), KM_STORE_OK);
}

static void prv_expect(bool asked, const km_flash_t *store, uint8_t id, uint32_t baud)
{
    km_boot_address_t at = {0xEEu, 0u};
    km_boot_address(&s_sh, asked, store, PRV_SCHEMA, &at);
    assert_int_equal(at.id, id);
    assert_int_equal(at.baud, baud);
}

/* §3: ENTER's ID and baud, round trip, with and without the store reader
 * (the handed-over pair wins over the stored one). */
static void test_handoff_round_trip(void **state)
{
    (void)state;
    static const uint8_t k_ids[] = {0u, 1u, 7u, 128u, 250u};
    static const uint32_t k_bauds[] = {9600u, 38400u, 57600u, 115200u, 500000u, 1000000u};
    prv_store(9u, 19200u);
    for (size_t i = 0; i < sizeof k_ids; i++) {
        for (size_t j = 0; j < sizeof k_bauds / sizeof k_bauds[0]; j++) {
            km_boot_handoff_set(&s_sh, k_ids[i], k_bauds[j]);
            prv_expect(true, NULL, k_ids[i], k_bauds[j]);
            prv_expect(true, &s_flash, k_ids[i], k_bauds[j]);
        }
    }
}

/* §3: a servo whose application does not start (no ENTER: not asked) is
 * found at the stored pair with the reader, at ID 1 / 115200 without it,
 * even if the word holds a sound pair from an earlier ENTER. */
static void test_not_asked_ignores_the_word(void **state)
{
    (void)state;
    km_boot_handoff_set(&s_sh, 5u, 57600u);
    prv_expect(false, NULL, 1u, 115200u);
    prv_expect(false, &s_flash, 0u, 115200u); /* blank store: ID 0 */
    prv_store(9u, 19200u);
    prv_expect(false, &s_flash, 9u, 19200u);
    prv_expect(false, NULL, 1u, 115200u);
}

/* Words the application did not leave: a wrong check byte, an ID over
 * 250 with a matching check, a baud outside 9600..1000000, all zero. */
static void test_unsound_words_fall_back(void **state)
{
    (void)state;
    static const uint32_t k_bad[] = {
        (1152u << 16) | (0xFBu << 8) | 0x05u,  /* check byte is not ~5 (0xFA) */
        (1152u << 16) | (0x04u << 8) | 0xFBu,  /* ID 251 */
        (95u << 16) | (0xFAu << 8) | 0x05u,    /* 9500 baud */
        (10001u << 16) | (0xFAu << 8) | 0x05u, /* 1000100 baud */
        0u,
        0xFFFFFFFFu,
    };
    for (size_t i = 0; i < sizeof k_bad / sizeof k_bad[0]; i++) {
        s_sh.address = k_bad[i];
        prv_expect(true, NULL, 1u, 115200u);
        prv_expect(true, &s_flash, 0u, 115200u);
    }
}

/* Power-on garbage: 100,000 xorshift words; a word is believed only when
 * it is sound (check byte, ID, baud), and then exactly as it decodes. */
static void test_garbage_is_believed_only_when_sound(void **state)
{
    (void)state;
    uint32_t x = 0x2545F491u;
    unsigned believed = 0u;
    for (unsigned n = 0; n < 100000u; n++) {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        s_sh.address = x;
        const uint8_t id = (uint8_t)x;
        const uint32_t baud = (x >> 16) * 100u;
        const bool sound =
            ((x >> 8) & 0xFFu) == (uint8_t)~id && id <= 250u && baud >= 9600u && baud <= 1000000u;
        km_boot_address_t at;
        km_boot_address(&s_sh, true, NULL, PRV_SCHEMA, &at);
        if (sound) {
            believed++;
            assert_int_equal(at.id, id);
            assert_int_equal(at.baud, baud);
        } else {
            assert_int_equal(at.id, 1u);
            assert_int_equal(at.baud, 115200u);
        }
    }
    assert_true(believed < 100000u / 256u * 2u); /* about 1 in 256 x 250/256 x 9905/65536 */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_handoff_round_trip, prv_setup),
        cmocka_unit_test_setup(test_not_asked_ignores_the_word, prv_setup),
        cmocka_unit_test_setup(test_unsound_words_fall_back, prv_setup),
        cmocka_unit_test_setup(test_garbage_is_believed_only_when_sound, prv_setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
