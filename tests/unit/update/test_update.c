/* SPDX-License-Identifier: Apache-2.0 */
/* The update state machine and its 0x78 frames (docs/update.md §2-§4) on
 * the NOR simulator: a whole update, every bad input of the table in §4
 * with its outcome, the wrong-model refusal before any erase, the commit
 * cell, re-sends, STATUS bitmaps, three servos taking one broadcast image,
 * and the application's side of 0x78. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_boot_check.h"
#include "km_update_proto.h"
#include "km_update_rig.h"

static rig_t s_r;
static km_update_t s_u;
static rig_image_t s_old, s_new;
static km_update_answer_t s_a;

static int prv_setup(void **state)
{
    (void)state;
    rig_init(&s_r, 1024u, 4u, 8u, 6u, 0xFFu); /* nRF51 geometry, 6 KiB region */
    km_update_init(&s_u, &s_r.region, &s_r.target);
    rig_make_image(&s_old, 3000u, 0x00100100u, KM_MODEL_STM32G031, 11u);
    rig_make_image(&s_new, 4001u, 0x00100200u, KM_MODEL_STM32G031, 22u);
    return 0;
}

static void prv_frame(const uint8_t *body, uint8_t n)
{
    km_update_frame(&s_u, body, n, &s_a);
}

static void prv_begin(const rig_image_t *im)
{
    uint8_t body[1 + KM_IMAGE_HEADER_SIZE] = {KM_UPD_SUB_BEGIN};
    memcpy(body + 1, im->bytes, KM_IMAGE_HEADER_SIZE);
    prv_frame(body, sizeof body);
}

static void prv_write(const rig_image_t *im, uint32_t b)
{
    uint8_t body[KM_BODY_MAX_TEST];
    prv_frame(body, rig_write_body(im, b, body));
}

static void prv_simple(uint8_t sub)
{
    prv_frame(&sub, 1u);
}

/* BEGIN, every block, VERIFY, COMMIT; each must succeed. */
static void prv_full_update(const rig_image_t *im)
{
    prv_begin(im);
    assert_int_equal(s_a.body[1], KM_UPD_OK);
    for (uint32_t b = 0; b < rig_blocks(im); b++) {
        prv_write(im, b);
        assert_int_equal(s_a.body[1], KM_UPD_OK);
    }
    prv_simple(KM_UPD_SUB_VERIFY);
    assert_int_equal(s_a.body[1], KM_UPD_OK);
    prv_simple(KM_UPD_SUB_COMMIT);
    assert_int_equal(s_a.body[1], KM_UPD_OK);
    assert_int_equal(s_u.state, KM_UPD_STATE_COMMITTED);
}

static void prv_assert_boots(const rig_image_t *im)
{
    km_image_header_t h;
    assert_true(km_boot_check(&s_r.region, &s_r.target, &h));
    assert_int_equal(h.version, im->version);
    uint8_t buf[RIG_MAX_IMAGE];
    assert_int_equal(s_r.region.read(s_r.region.ctx, 0u, buf, im->length), KM_FLASH_OK);
    assert_memory_equal(buf, im->bytes, im->length);
}

/* CRC-32 is zlib's: the standard check value. */
static void test_crc32_is_ieee(void **state)
{
    (void)state;
    assert_int_equal(km_crc32(0u, (const uint8_t *)"123456789", 9u), 0xCBF43926u);
}

/* §4: a whole update on a blank region boots the new image, byte for byte;
 * the answers carry the sub-command, the result and the block. */
static void test_whole_update_boots_new_image(void **state)
{
    (void)state;
    assert_false(km_boot_check(&s_r.region, &s_r.target, NULL));
    prv_begin(&s_new);
    assert_int_equal(s_a.len, 2);
    assert_int_equal(s_a.body[0], KM_UPD_SUB_BEGIN);
    prv_write(&s_new, 1u);
    assert_int_equal(s_a.len, 4);
    assert_int_equal(s_a.body[0], KM_UPD_SUB_WRITE);
    assert_int_equal(s_a.body[1], KM_UPD_OK);
    assert_int_equal(s_a.body[2], 1);
    assert_int_equal(s_a.body[3], 0);
    for (uint32_t b = 0; b < rig_blocks(&s_new); b++) {
        prv_write(&s_new, b);
        assert_int_equal(s_a.body[1], KM_UPD_OK);
    }
    prv_simple(KM_UPD_SUB_VERIFY);
    assert_int_equal(s_a.len, 6);
    assert_int_equal(s_a.body[1], KM_UPD_OK);
    const uint32_t crc = (uint32_t)s_a.body[2] | ((uint32_t)s_a.body[3] << 8) |
                         ((uint32_t)s_a.body[4] << 16) | ((uint32_t)s_a.body[5] << 24);
    assert_int_equal(crc, km_crc32(0u, s_new.bytes, s_new.length));
    /* §2 commit cell: verified, but not bootable before COMMIT. */
    assert_false(km_boot_check(&s_r.region, &s_r.target, NULL));
    prv_simple(KM_UPD_SUB_COMMIT);
    assert_int_equal(s_a.body[1], KM_UPD_OK);
    prv_assert_boots(&s_new);
    assert_int_equal(s_r.sim.count.violations, 0);
    assert_int_equal(s_r.sim.count.align_errors, 0);
}

/* §4: an image for another board is refused before anything is erased:
 * no flash operation at all, the old image still boots. */
static void test_wrong_model_refused_before_erase(void **state)
{
    (void)state;
    prv_full_update(&s_old);
    km_nor_sim_power_cycle(&s_r.sim);
    km_update_init(&s_u, &s_r.region, &s_r.target);
    rig_image_t other;
    rig_make_image(&other, 2000u, 0x00100300u, KM_MODEL_QEMU_MICROBIT, 5u);
    prv_begin(&other);
    assert_int_equal(s_a.body[1], KM_UPD_WRONG_MODEL);
    assert_int_equal(km_nor_sim_ops(&s_r.sim), 0);
    assert_int_equal(s_u.state, KM_UPD_STATE_IDLE);
    prv_assert_boots(&s_old);
}

/* §4 table: BEGIN's bad headers and lengths, nothing erased each time. */
static void test_begin_bad_inputs_erase_nothing(void **state)
{
    (void)state;
    prv_full_update(&s_old);
    km_nor_sim_power_cycle(&s_r.sim);
    km_update_init(&s_u, &s_r.region, &s_r.target);
    struct {
        uint32_t off, value;
        uint8_t expect;
        int fix_crc;
    } cases[] = {
        {0, 0x57464D4Cu, KM_UPD_BAD_HEADER, 1},  /* magic */
        {28, 0x12345678u, KM_UPD_BAD_HEADER, 0}, /* header CRC */
        {16, 0x200u, KM_UPD_BAD_HEADER, 1},      /* vectors */
        {20, 0x08002000u, KM_UPD_BAD_HEADER, 1}, /* base */
        {8, KM_IMAGE_MIN_LEN - 1u, KM_UPD_TOO_BIG, 1},
        {8, 6u * 1024u + 1u, KM_UPD_TOO_BIG, 1}, /* above the region */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        rig_image_t im = s_new;
        rig_put32(im.bytes + cases[i].off, cases[i].value);
        if (cases[i].fix_crc) {
            rig_put32(im.bytes + 28, km_crc32(0u, im.bytes, 28u));
        }
        prv_begin(&im);
        assert_int_equal(s_a.body[1], cases[i].expect);
        assert_int_equal(s_u.state, KM_UPD_STATE_IDLE);
    }
    const uint8_t short_begin[5] = {KM_UPD_SUB_BEGIN, 0x4B, 0x4D, 0x46, 0x57};
    prv_frame(short_begin, sizeof short_begin);
    assert_int_equal(s_a.body[1], KM_UPD_BAD_LENGTH);
    assert_int_equal(km_nor_sim_ops(&s_r.sim), 0);
    prv_assert_boots(&s_old);
}

/* §4 table: WRITE's bad inputs. */
static void test_write_bad_inputs(void **state)
{
    (void)state;
    prv_write(&s_new, 0u);
    assert_int_equal(s_a.body[1], KM_UPD_BAD_STATE); /* IDLE */
    prv_begin(&s_new);
    const uint32_t ops = km_nor_sim_ops(&s_r.sim);
    uint8_t body[KM_BODY_MAX_TEST];
    uint8_t n = rig_write_body(&s_new, rig_blocks(&s_new), body);
    prv_frame(body, n);
    assert_int_equal(s_a.body[1], KM_UPD_BAD_BLOCK);
    n = rig_write_body(&s_new, 3u, body);
    body[10] ^= 0x01u; /* data no longer matches its CRC */
    prv_frame(body, n);
    assert_int_equal(s_a.body[1], KM_UPD_BAD_CRC);
    prv_frame(body, (uint8_t)(n - 1u));
    assert_int_equal(s_a.body[1], KM_UPD_BAD_LENGTH);
    rig_image_t other = s_new; /* block 0 of another header */
    rig_put32(other.bytes + 12, 0x00999999u);
    prv_write(&other, 0u);
    assert_int_equal(s_a.body[1], KM_UPD_MISMATCH);
    assert_int_equal(km_nor_sim_ops(&s_r.sim), ops); /* none of them programmed */
    /* A re-send of the same data: OK, nothing programmed; other data: MISMATCH. */
    prv_write(&s_new, 3u);
    assert_int_equal(s_a.body[1], KM_UPD_OK);
    const uint32_t ops2 = km_nor_sim_ops(&s_r.sim);
    prv_write(&s_new, 3u);
    assert_int_equal(s_a.body[1], KM_UPD_OK);
    assert_int_equal(km_nor_sim_ops(&s_r.sim), ops2);
    rig_image_t changed = s_new;
    changed.bytes[3u * KM_UPDATE_BLOCK + 7u] ^= 0xFFu;
    prv_write(&changed, 3u);
    assert_int_equal(s_a.body[1], KM_UPD_MISMATCH);
    assert_int_equal(km_nor_sim_ops(&s_r.sim), ops2);
    assert_int_equal(s_u.state, KM_UPD_STATE_RECEIVING);
    assert_int_equal(s_u.received, 1);
}

/* §4 table: VERIFY with blocks missing, VERIFY after the flash changed
 * behind the servo's back, COMMIT before VERIFY, WRITE after VERIFY. */
static void test_verify_and_commit_bad_inputs(void **state)
{
    (void)state;
    prv_simple(KM_UPD_SUB_VERIFY);
    assert_int_equal(s_a.body[1], KM_UPD_BAD_STATE);
    prv_begin(&s_new);
    for (uint32_t b = 1; b < rig_blocks(&s_new); b++) {
        prv_write(&s_new, b);
    }
    prv_simple(KM_UPD_SUB_VERIFY);
    assert_int_equal(s_a.body[1], KM_UPD_MISSING);
    assert_int_equal(s_u.state, KM_UPD_STATE_RECEIVING);
    prv_simple(KM_UPD_SUB_COMMIT);
    assert_int_equal(s_a.body[1], KM_UPD_BAD_STATE);
    const uint8_t verify_long[2] = {KM_UPD_SUB_VERIFY, 0};
    prv_frame(verify_long, 2);
    assert_int_equal(s_a.body[1], KM_UPD_BAD_LENGTH);
    prv_write(&s_new, 0u);
    s_r.sim.data[2000] ^= 0x10u; /* a bit lost in a programmed cell */
    prv_simple(KM_UPD_SUB_VERIFY);
    assert_int_equal(s_a.body[1], KM_UPD_VERIFY_FAIL);
    assert_int_equal(s_u.state, KM_UPD_STATE_FAILED);
    prv_write(&s_new, 1u);
    assert_int_equal(s_a.body[1], KM_UPD_BAD_STATE);
    assert_false(km_boot_check(&s_r.region, &s_r.target, NULL));
    /* A new BEGIN starts over and finishes. */
    prv_full_update(&s_new);
    prv_write(&s_new, 1u);
    assert_int_equal(s_a.body[1], KM_UPD_BAD_STATE); /* COMMITTED */
    prv_assert_boots(&s_new);
}

/* §4: ENTER and START magics; unknown and missing sub-commands. */
static void test_enter_start_and_unknown(void **state)
{
    (void)state;
    prv_begin(&s_new);
    const uint8_t bad_enter[5] = {KM_UPD_SUB_ENTER, 0xB1, 0xB2, 0xB3, 0xB5};
    prv_frame(bad_enter, 5);
    assert_int_equal(s_a.len, 0);
    assert_int_equal(s_u.result, KM_UPD_BAD_MAGIC);
    assert_int_equal(s_u.state, KM_UPD_STATE_RECEIVING);
    const uint8_t enter[5] = {KM_UPD_SUB_ENTER, 0xB1, 0xB2, 0xB3, 0xB4};
    prv_frame(enter, 5);
    assert_int_equal(s_a.len, 0);
    assert_int_equal(s_u.state, KM_UPD_STATE_IDLE);
    const uint8_t bad_start[5] = {KM_UPD_SUB_START, 0xE1, 0xE2, 0xE3, 0xE3};
    prv_frame(bad_start, 5);
    assert_int_equal(s_a.body[1], KM_UPD_BAD_MAGIC);
    assert_int_equal(s_a.action, KM_UPD_ACT_NONE);
    const uint8_t start[5] = {KM_UPD_SUB_START, 0xE1, 0xE2, 0xE3, 0xE4};
    prv_frame(start, 5);
    assert_int_equal(s_a.len, 0);
    assert_int_equal(s_a.action, KM_UPD_ACT_RESTART);
    for (unsigned sub = 0; sub < 256u; sub++) {
        if (sub >= KM_UPD_SUB_ENTER && sub <= KM_UPD_SUB_START) {
            continue;
        }
        const uint8_t b = (uint8_t)sub;
        prv_frame(&b, 1);
        assert_int_equal(s_a.action, KM_UPD_ACT_EXCEPTION);
        assert_int_equal(s_a.len, 0);
    }
    prv_frame(NULL, 0);
    assert_int_equal(s_a.action, KM_UPD_ACT_EXCEPTION);
}

/* §4 STATUS: the bitmap of received blocks from `first`, 64 bytes at most;
 * a `first` that is not a multiple of 8, or beyond the blocks, is refused. */
static void test_status_bitmap(void **state)
{
    (void)state;
    prv_begin(&s_new); /* 4001 bytes: 32 blocks */
    for (uint32_t b = 0; b < rig_blocks(&s_new); b++) {
        if (b != 9u && b != 31u) {
            prv_write(&s_new, b);
        }
    }
    const uint8_t st[3] = {KM_UPD_SUB_STATUS, 0, 0};
    prv_frame(st, 3);
    assert_int_equal(s_a.len, 9 + 4);
    const uint8_t expect[13] = {
        KM_UPD_SUB_STATUS, KM_UPD_STATE_RECEIVING, KM_UPD_OK, 32, 0, 30, 0, 0, 0, 0xFF, 0xFD, 0xFF, 0x7F};
    assert_memory_equal(s_a.body, expect, sizeof expect);
    const uint8_t st8[3] = {KM_UPD_SUB_STATUS, 8, 0};
    prv_frame(st8, 3);
    assert_int_equal(s_a.len, 9 + 3);
    assert_int_equal(s_a.body[9], 0xFD);
    const uint8_t odd[3] = {KM_UPD_SUB_STATUS, 3, 0};
    prv_frame(odd, 3);
    assert_int_equal(s_a.body[2], KM_UPD_BAD_LENGTH);
    assert_int_equal(s_a.len, 9);
    const uint8_t beyond[3] = {KM_UPD_SUB_STATUS, 32, 0};
    prv_frame(beyond, 3);
    assert_int_equal(s_a.body[2], KM_UPD_BAD_LENGTH);
    const uint8_t none[1] = {KM_UPD_SUB_STATUS};
    prv_frame(none, 1);
    assert_int_equal(s_a.body[2], KM_UPD_BAD_LENGTH);
}

/* §4 "A whole-robot update": three servos take the same broadcast frames;
 * one misses a block, STATUS shows it on that servo only, the re-send
 * completes it and is a no-op on the others. */
static void test_three_servos_one_broadcast(void **state)
{
    (void)state;
    static rig_t r[3];
    static km_update_t u[3];
    static rig_window_t win[3];
    km_flash_t region[3];
    for (int i = 0; i < 3; i++) {
        rig_init(&r[i], 2048u, 8u, 4u, 3u, 0xFFu); /* STM32G0 geometry */
        win[i] = s_rig_win_region;                 /* each servo its own window */
        region[i] = r[i].region;
        region[i].ctx = &win[i];
        km_update_init(&u[i], &region[i], &r[i].target);
    }
    uint8_t body[KM_BODY_MAX_TEST];
    uint8_t begin[1 + KM_IMAGE_HEADER_SIZE] = {KM_UPD_SUB_BEGIN};
    memcpy(begin + 1, s_new.bytes, KM_IMAGE_HEADER_SIZE);
    for (int i = 0; i < 3; i++) {
        km_update_frame(&u[i], begin, sizeof begin, &s_a);
    }
    for (uint32_t b = 0; b < rig_blocks(&s_new); b++) {
        uint8_t n = rig_write_body(&s_new, b, body);
        for (int i = 0; i < 3; i++) {
            if (!(i == 1 && b == 17u)) { /* servo 2 loses block 17 */
                km_update_frame(&u[i], body, n, &s_a);
            }
        }
    }
    for (int i = 0; i < 3; i++) {
        assert_int_equal(km_update_has(&u[i], 17u), i != 1);
    }
    const uint8_t st[3] = {KM_UPD_SUB_STATUS, 16, 0};
    km_update_frame(&u[1], st, 3, &s_a);
    assert_int_equal(s_a.body[9], 0xFD); /* block 17 = bit 1 of the byte from 16 */
    uint8_t n = rig_write_body(&s_new, 17u, body);
    for (int i = 0; i < 3; i++) {
        km_update_frame(&u[i], body, n, &s_a);
        assert_int_equal(s_a.body[1], KM_UPD_OK);
        const uint8_t v = KM_UPD_SUB_VERIFY;
        km_update_frame(&u[i], &v, 1, &s_a);
        assert_int_equal(s_a.body[1], KM_UPD_OK);
        const uint8_t c = KM_UPD_SUB_COMMIT;
        km_update_frame(&u[i], &c, 1, &s_a);
        assert_int_equal(s_a.body[1], KM_UPD_OK);
        km_image_header_t h;
        assert_true(km_boot_check(&region[i], &r[i].target, &h));
        assert_int_equal(h.version, s_new.version);
        assert_int_equal(r[i].sim.count.violations, 0);
    }
}

/* §4, application column: ENTER restarts into the bootloader, STATUS says
 * state 0, the other sub-commands are bit 5 there. */
static void test_application_side(void **state)
{
    (void)state;
    const uint8_t enter[5] = {KM_UPD_SUB_ENTER, 0xB1, 0xB2, 0xB3, 0xB4};
    km_update_app_frame(enter, 5, &s_a);
    assert_int_equal(s_a.action, KM_UPD_ACT_ENTER);
    assert_int_equal(s_a.len, 0);
    const uint8_t bad[5] = {KM_UPD_SUB_ENTER, 0xE1, 0xE2, 0xE3, 0xE4};
    km_update_app_frame(bad, 5, &s_a);
    assert_int_equal(s_a.action, KM_UPD_ACT_EXCEPTION);
    km_update_app_frame(enter, 4, &s_a);
    assert_int_equal(s_a.action, KM_UPD_ACT_EXCEPTION);
    const uint8_t st[3] = {KM_UPD_SUB_STATUS, 0, 0};
    km_update_app_frame(st, 3, &s_a);
    assert_int_equal(s_a.action, KM_UPD_ACT_NONE);
    const uint8_t expect[9] = {KM_UPD_SUB_STATUS, KM_UPD_STATE_APP, 0, 0, 0, 0, 0, 0, 0};
    assert_int_equal(s_a.len, 9);
    assert_memory_equal(s_a.body, expect, 9);
    for (uint8_t sub = KM_UPD_SUB_BEGIN; sub <= KM_UPD_SUB_START; sub++) {
        if (sub != KM_UPD_SUB_STATUS) {
            km_update_app_frame(&sub, 1, &s_a);
            assert_int_equal(s_a.action, KM_UPD_ACT_EXCEPTION);
        }
    }
    km_update_app_frame(NULL, 0, &s_a);
    assert_int_equal(s_a.action, KM_UPD_ACT_EXCEPTION);
}

/* §3: the boot check refuses a region whose header reads with an ECC
 * error, and one whose body lost a bit. */
static void test_boot_check_refuses_damage(void **state)
{
    (void)state;
    prv_full_update(&s_new);
    s_r.sim.data[1000] ^= 0x01u;
    assert_false(km_boot_check(&s_r.region, &s_r.target, NULL));
    s_r.sim.data[1000] ^= 0x01u;
    assert_true(km_boot_check(&s_r.region, &s_r.target, NULL));
    km_image_target_t other = s_r.target;
    other.model = KM_MODEL_QEMU_MICROBIT;
    assert_false(km_boot_check(&s_r.region, &other, NULL));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc32_is_ieee),
        cmocka_unit_test_setup(test_whole_update_boots_new_image, prv_setup),
        cmocka_unit_test_setup(test_wrong_model_refused_before_erase, prv_setup),
        cmocka_unit_test_setup(test_begin_bad_inputs_erase_nothing, prv_setup),
        cmocka_unit_test_setup(test_write_bad_inputs, prv_setup),
        cmocka_unit_test_setup(test_verify_and_commit_bad_inputs, prv_setup),
        cmocka_unit_test_setup(test_enter_start_and_unknown, prv_setup),
        cmocka_unit_test_setup(test_status_bitmap, prv_setup),
        cmocka_unit_test_setup(test_three_servos_one_broadcast, prv_setup),
        cmocka_unit_test_setup(test_application_side, prv_setup),
        cmocka_unit_test_setup(test_boot_check_refuses_damage, prv_setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
