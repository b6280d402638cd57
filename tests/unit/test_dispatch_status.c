/* PROTOCOL.md §4 status byte, §3 answer rules (response level, own /
 * broadcast / super ID) and the super-ID answer slots. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_test_support.h"

#define ID 7
static kt_fx_t fx;

static void make_failed(void)  /* bit 6: an out-of-range write (§4) */
{
    kt_write_u8(&fx, ID, 0x64, 9);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
}

static void make_exception(void) /* bit 5: a reserved address (§4) */
{
    kt_write_u8(&fx, ID, 0x20, 1);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION);
}

/* Frames for other IDs do not touch bits 5/6. */
static void frames_for_others(void)
{
    kt_ping(&fx, ID + 1);
    kt_read(&fx, ID + 1, 0x13);
    kt_write_u8(&fx, ID + 1, 0x11, 0x0A);
    kt_write_u8(&fx, 0, 0x64, 9);
    kt_no_reply(&fx);
}

/* §4 bit 6: set by a failed command, kept through frames for other IDs,
 * cleared by the next command to our own ID. */
static void test_s4_bit6_cleared_by_next_own_command(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    make_failed();
    frames_for_others();
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
    /* The ping reports the failed write (a master at response level 0 has
     * no other way to see it), then the bit is cleared. */
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, KM_ST_FAILED);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, 0);
}

/* ... by a broadcast command. */
static void test_s4_bit6_cleared_by_broadcast(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    make_failed();
    kt_write_u8(&fx, KM_ID_BROADCAST, 0x32, 0x0F);
    kt_no_reply(&fx);
    assert_int_equal(km_servo_status(&fx.s), 0);
}

/* ... by a super-ID ping or read (it answers with the fresh status). */
static void test_s4_bit6_cleared_by_super_ping_and_read(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    make_failed();
    kt_ping(&fx, KM_ID_SUPER);
    kt_reply_is_status(&fx, ID, KM_ST_FAILED); /* reported, then cleared */
    assert_int_equal(km_servo_status(&fx.s), 0);
    make_failed();
    kt_read(&fx, KM_ID_SUPER, 0x13);
    assert_int_equal(km_servo_status(&fx.s), 0);
}

/* Decision "Super ID": a write to the super ID is ignored and so is not "the
 * next command": bits stay. */
static void test_s4_super_write_ignored_bits_stay(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    make_failed();
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_write_u16(&fx, KM_ID_SUPER, 0x13, 500);
    kt_no_reply(&fx);
    kt_assert_unchanged(&fx, &sn);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
}

/* §4 bit 5: same life cycle as bit 6. */
static void test_s4_bit5_set_and_cleared(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    make_exception();
    frames_for_others();
    assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION); /* reported, then cleared */
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, 0);
    make_exception();
    kt_ping(&fx, KM_ID_SUPER);
    kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
    assert_int_equal(km_servo_status(&fx.s), 0);
    make_exception();
    kt_write_u8(&fx, KM_ID_BROADCAST, 0x32, 0x0F);
    assert_int_equal(km_servo_status(&fx.s), 0);
}

/* §4 bit 5 and 6 describe the last command only: a good command after a
 * failed one answers 0; a failing one after an exception shows only bit 6. */
static void test_s4_bits_describe_last_command(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    make_exception();
    make_failed();
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
}

/* §4 Decision: a bad-checksum frame with our ID: bit 5 in the next answer. */
static void test_s4_checksum_error_sets_bit5_for_next_answer(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    km_servo_note_checksum_error(&fx.s);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, 0);
}

/* §4 bit 4: latched from live hardware faults until re-init (restart);
 * 0x35 reads the latched flags. Motion is blocked meanwhile. */
static void test_s4_bit4_latched_until_reinit(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    km_live_t live = {0};
    live.hw_faults = 0x20; /* position sensor */
    km_servo_set_live(&fx.s, &live);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, KM_ST_HW_FAULT);
    live.hw_faults = 0;
    km_servo_set_live(&fx.s, &live);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, KM_ST_HW_FAULT);
    kt_read(&fx, ID, 0x35);
    const uint8_t want = 0x20;
    kt_reply_is_read(&fx, ID, 0x35, &want, 1);
    /* reads and writes still work, motion does not (§5.2 0x35) */
    kt_write_u16(&fx, ID, 0x13, 500);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_MAX_TORQUE), 500);
    const uint8_t mv[] = {0x84, 0x03, 0xE8, 0x03};
    kt_write(&fx, ID, 0x65, mv, 4);
    assert_int_equal(fx.fake.n_requests, 0);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_HW_FAULT | KM_ST_FAILED);
    kt_init(&fx, kt_product_pot(), ID); /* restart = re-init */
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, 0);
}

/* §4 bits 7 and 0..3 follow live state both ways; 0x36 reads the protections. */
static void test_s4_bit7_and_protection_bits_live(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    km_live_t live = {0};
    live.running = true;
    live.protections = 0x05; /* bit2 temperature, bit0 voltage */
    km_servo_set_live(&fx.s, &live);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, 0x80 | 0x05);
    kt_read(&fx, ID, 0x36);
    const uint8_t p = 0x05;
    kt_reply_is_read(&fx, ID, 0x36, &p, 1);
    live.running = false;
    live.protections = 0x08;
    km_servo_set_live(&fx.s, &live);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, 0x08);
    live.protections = 0;
    km_servo_set_live(&fx.s, &live);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, 0);
}

/* §3 response level (0x11 bit 3): 0 = only ping and read answer; 1 = writes
 * to our own ID answer too; broadcast writes never answer. */
static void test_s3_response_level(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_write_u16(&fx, ID, 0x13, 800); /* default 0x02: level 0 */
    kt_no_reply(&fx);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_MAX_TORQUE), 800);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, 0);
    kt_read(&fx, ID, 0x13);
    const uint8_t v[] = {0x20, 0x03};
    kt_reply_is_read(&fx, ID, 0x13, v, 2);
    kt_write_u8(&fx, ID, 0x11, 0x0A); /* level 1: this write already answers */
    kt_reply_is_status(&fx, ID, 0);
    kt_write_u16(&fx, ID, 0x13, 700);
    kt_reply_is_status(&fx, ID, 0);
    kt_write_u16(&fx, ID, 0x13, 1001);
    kt_reply_is_status(&fx, ID, KM_ST_FAILED);
    kt_write_u16(&fx, KM_ID_BROADCAST, 0x13, 600);
    kt_no_reply(&fx);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_MAX_TORQUE), 600);
    kt_write_u8(&fx, ID, 0x11, 0x02); /* back to level 0: no answer */
    kt_no_reply(&fx);
}

/* §3: ping and read with own, broadcast and super ID. */
static void test_s3_ping_read_own_broadcast_super(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_ping(&fx, KM_ID_BROADCAST);
    kt_no_reply(&fx);
    kt_read(&fx, KM_ID_BROADCAST, 0x13);
    kt_no_reply(&fx);
    const uint8_t v[] = {0xE8, 0x03};
    kt_read(&fx, ID, 0x13);
    kt_reply_is_read(&fx, ID, 0x13, v, 2);
    assert_int_equal(fx.reply.delay_us, 200);
    kt_read(&fx, KM_ID_SUPER, 0x13);
    kt_reply_is_read(&fx, ID, 0x13, v, 2); /* answered with the own ID */
    kt_ping(&fx, KM_ID_SUPER);
    kt_reply_is_status(&fx, ID, 0);
}

/* "Super-ID answer slots": delay = 0x12 + id x ceil(((answer_bytes + 2) x 10
 * bits) x 1e6 / baud) us, answer_bytes = the longest answer of the request. */
static void test_s3_super_id_slots_ping(void **state)
{
    (void)state;
    /* Worked by hand at 115200: (6 + 2) x 10 = 80 bits = 694.4 us -> 695. */
    assert_int_equal(kt_slot_us(6, 115200), 695);
    static const uint8_t ids[] = {0, 1, 2, 7, 100, 250};
    for (unsigned i = 0; i < sizeof ids; i++) {
        kt_init(&fx, kt_product_pot(), ids[i]);
        kt_ping(&fx, KM_ID_SUPER);
        kt_reply_is_status(&fx, ids[i], 0);
        assert_int_equal(fx.reply.delay_us, 200u + ids[i] * kt_slot_us(6, 115200));
        kt_ping(&fx, ids[i]);
        assert_int_equal(fx.reply.delay_us, 200u); /* own ID: no slot */
    }
}

static void check_super_read(uint8_t addr, unsigned longest_value, uint32_t baud, uint16_t delay)
{
    static const uint8_t ids[] = {0, 1, 3, 250};
    for (unsigned i = 0; i < sizeof ids; i++) {
        kt_init(&fx, kt_product_pot(), ids[i]);
        if (baud != 115200u || delay != 200u) { /* via the store: baud applies at init */
            for (unsigned k = 0, j = 0; j < KM_REG_COUNT; j++) {
                if (!km_reg_table[j].persisted) continue;
                if (km_reg_table[j].addr == 0x10) fx.persisted[k] = baud / 100u;
                if (km_reg_table[j].addr == 0x12) fx.persisted[k] = delay;
                k++;
            }
            km_servo_init(&fx.s, kt_product_pot(), fx.persisted, 1, &fx.ops);
        }
        assert_int_equal(km_servo_active_baud(&fx.s), baud);
        kt_read(&fx, KM_ID_SUPER, addr);
        assert_int_equal(fx.reply.bytes[5], addr);
        /* read answer: F9 F5 id len 02 adr value cs = 7 + value bytes */
        assert_int_equal(fx.reply.delay_us, delay + ids[i] * kt_slot_us(7u + longest_value, baud));
    }
}

/* Read of 0x46: the longest answer is i32 (11 bytes) even when the position
 * fits an i16: 130 bits at 115200 = 1128.5 us -> 1129 per slot. */
static void test_s3_super_id_slots_read_0x46(void **state)
{
    (void)state;
    assert_int_equal(kt_slot_us(11, 115200), 1129);
    check_super_read(0x46, 4, 115200, 200);
    assert_int_equal(fx.reply.len, 9); /* position 0 answers as i16 */
}

static void test_s3_super_id_slots_other_registers_and_baud(void **state)
{
    (void)state;
    check_super_read(0x13, 2, 115200, 200);
    check_super_read(0x01, 2, 115200, 200);
    check_super_read(0x3E, 3, 115200, 200);
    check_super_read(0x0A, 16, 115200, 200); /* model text: up to 16 B */
    check_super_read(0x0B, 4, 115200, 200);
    check_super_read(0x46, 4, 9600, 1000);
    assert_int_equal(kt_slot_us(6, 9600), 8334); /* 80 bits: 8333.3 us */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s4_bit6_cleared_by_next_own_command),
        cmocka_unit_test(test_s4_bit6_cleared_by_broadcast),
        cmocka_unit_test(test_s4_bit6_cleared_by_super_ping_and_read),
        cmocka_unit_test(test_s4_super_write_ignored_bits_stay),
        cmocka_unit_test(test_s4_bit5_set_and_cleared),
        cmocka_unit_test(test_s4_bits_describe_last_command),
        cmocka_unit_test(test_s4_checksum_error_sets_bit5_for_next_answer),
        cmocka_unit_test(test_s4_bit4_latched_until_reinit),
        cmocka_unit_test(test_s4_bit7_and_protection_bits_live),
        cmocka_unit_test(test_s3_response_level),
        cmocka_unit_test(test_s3_ping_read_own_broadcast_super),
        cmocka_unit_test(test_s3_super_id_slots_ping),
        cmocka_unit_test(test_s3_super_id_slots_read_0x46),
        cmocka_unit_test(test_s3_super_id_slots_other_registers_and_baud),
    };
    return cmocka_run_group_tests_name("dispatch_status", tests, NULL, NULL);
}
