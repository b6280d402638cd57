/* SPDX-License-Identifier: Apache-2.0 */
/* docs/protocol.md §4 status byte, §3 answer rules (response level, own /
 * broadcast / super ID) and the super-ID answer slots. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_test_support.h"

#define ID 7
static kt_fx_t fx;

static void make_failed(void) /* bit 6: an out-of-range write (§4) */
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

/* §4 bit 6 with "One life cycle for bits 5 and 6": set by a failed
 * level-0 write, kept through frames for other IDs, reported once by the
 * next ping. */
static void test_s4_bit6_reported_by_next_ping(void **state)
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

/* "One life cycle for bits 5 and 6" rule 5: a broadcast write gets no
 * answer, so it reports nothing: an earlier failure stays unreported, and a
 * failing broadcast write adds its own bit 6. */
static void test_s4_bit6_kept_through_broadcast_write(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    make_failed();
    kt_write_u8(&fx, KM_ID_BROADCAST, 0x32, 0x0F);
    kt_no_reply(&fx);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    kt_ping_is(&fx, ID, 0);
    kt_write_u16(&fx, KM_ID_BROADCAST, 0x13, 1001); /* out of range */
    kt_no_reply(&fx);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_MAX_TORQUE), 1000);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    kt_ping_is(&fx, ID, 0);
}

/* Rule 3: a super-ID ping and a super-ID read of 0x01 report the unreported
 * bits and clear them; rule 4: a super-ID read of another register answers
 * a value with no status byte and leaves them. */
static void test_s4_super_ping_and_0x01_report_other_super_reads_keep(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    make_failed();
    kt_ping(&fx, KM_ID_SUPER);
    kt_reply_is_status(&fx, ID, KM_ST_FAILED); /* reported, then cleared */
    assert_int_equal(km_servo_status(&fx.s), 0);
    make_failed();
    kt_read(&fx, KM_ID_SUPER, 0x13);
    const uint8_t v[] = {0xE8, 0x03};
    kt_reply_is_read(&fx, ID, 0x13, v, 2);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED); /* not reported yet */
    kt_read(&fx, KM_ID_SUPER, 0x01);
    assert_int_equal(fx.reply.len, 9);
    assert_int_equal(fx.reply.bytes[5], 0x01);
    assert_int_equal(fx.reply.bytes[6], KM_ST_FAILED);
    assert_int_equal(km_servo_status(&fx.s), 0);
    kt_ping_is(&fx, ID, 0);
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

/* §4 bit 5: the same life cycle as bit 6: kept through frames for others
 * and through a broadcast write, reported once by a ping (own or super). */
static void test_s4_bit5_set_and_reported_once(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    make_exception();
    frames_for_others();
    assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION);
    kt_ping_is(&fx, ID, KM_ST_EXCEPTION); /* reported, then cleared */
    kt_ping_is(&fx, ID, 0);
    make_exception();
    kt_ping(&fx, KM_ID_SUPER);
    kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
    assert_int_equal(km_servo_status(&fx.s), 0);
    make_exception();
    kt_write_u8(&fx, KM_ID_BROADCAST, 0x32, 0x0F); /* no answer: reports nothing */
    assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION);
    kt_ping_is(&fx, ID, KM_ST_EXCEPTION);
    kt_ping_is(&fx, ID, 0);
}

/* Rule 4: a write's own answer (response level 1) carries that write's bits
 * only: a good write after a failed one answers 0, an exception after a
 * failure answers bit 5 alone; the failure that no answer carried (a
 * level-0 write) is still reported, once, by the next ping. */
static void test_s4_own_answer_carries_own_bits_only(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    make_failed();                    /* response level 0: unanswered, bit 6 unreported */
    kt_write_u8(&fx, ID, 0x11, 0x0A); /* level 1: this write answers, for itself */
    kt_reply_is_status(&fx, ID, 0);
    kt_write_u16(&fx, ID, 0x13, 1001); /* fails: its own answer says so */
    kt_reply_is_status(&fx, ID, KM_ST_FAILED);
    kt_write_u16(&fx, ID, 0x13, 700); /* good after failed: 0 */
    kt_reply_is_status(&fx, ID, 0);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_MAX_TORQUE), 700);
    kt_write_u8(&fx, ID, 0x20, 1); /* reserved address: bit 5 alone, not 0x60 */
    kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
    kt_ping_is(&fx, ID, KM_ST_FAILED); /* the level-0 failure, once */
    kt_ping_is(&fx, ID, 0);
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
                if (!km_reg_table[j].persisted)
                    continue;
                if (km_reg_table[j].addr == 0x10)
                    fx.persisted[k] = baud / 100u;
                if (km_reg_table[j].addr == 0x12)
                    fx.persisted[k] = delay;
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

/* ---- "One life cycle for bits 5 and 6", every command kind ------------- */

/* How a command deals with the unreported bits (docs/protocol-decisions.md
 * "One life cycle for bits 5 and 6", rules 3..6). */
typedef enum {
    LC_ALL,     /* rule 3: answers unreported | own in its status byte, clears them */
    LC_OWN,     /* rule 4: a short response with its own bits; unreported stay */
    LC_VALUE,   /* rule 4: a value answer (no status byte); unreported stay */
    LC_NONE,    /* rule 5: no answer, its own bits join the unreported ones */
    LC_IGNORED, /* rule 6: no answer, nothing changes (own must be 0) */
} lc_kind_t;

typedef struct {
    const char *name;
    uint8_t level;     /* response level (0x11 bit 3) when the command is sent */
    const char *pre;   /* sent after the prior state, before the command (or NULL) */
    const char *frame; /* the command, whole, checksum checked by the helper */
    lc_kind_t kind;
    uint8_t own;        /* the command's own bits 5/6 */
    const char *answer; /* LC_VALUE: the exact answer */
    bool read01;        /* LC_ALL answered as a read of 0x01: the status is its first value byte */
} lc_case_t;

#define LC_ID 1
#define PING_1 "F9 FF 01 02 01 FB"

static const lc_case_t lc_cases[] = {
    {"ping own", 0, NULL, PING_1, LC_ALL, 0, NULL, false},
    {"ping own with a parameter", 0, NULL, "F9 FF 01 03 01 00 FA", LC_ALL, KM_ST_EXCEPTION, NULL, false},
    {"ping super", 0, NULL, "F9 FF FD 02 01 FF", LC_ALL, 0, NULL, false},
    {"ping broadcast", 0, NULL, "F9 FF FE 02 01 FE", LC_NONE, 0, NULL, false},
    {"read own ok", 0, NULL, "F9 FF 01 03 02 13 E6", LC_VALUE, 0, "F9 F5 01 05 02 13 E8 03 F9", false},
    {"read own error", 0, NULL, "F9 FF 01 03 02 20 D9", LC_OWN, KM_ST_EXCEPTION, NULL, false},
    {"read own 0x01", 0, NULL, "F9 FF 01 03 02 01 F8", LC_ALL, 0, NULL, true},
    {"read super 0x01", 0, NULL, "F9 FF FD 03 02 01 FC", LC_ALL, 0, NULL, true},
    {"read super", 0, NULL, "F9 FF FD 03 02 13 EA", LC_VALUE, 0, "F9 F5 01 05 02 13 E8 03 F9", false},
    {"read broadcast", 0, NULL, "F9 FF FE 03 02 13 E9", LC_NONE, 0, NULL, false},
    {"0x7F own ok", 0, NULL, "F9 FF 01 03 7F 01 7B", LC_VALUE, 0, "F9 F5 01 04 7F 01 00 7A", false},
    {"0x7F own error", 0, NULL, "F9 FF 01 03 7F 09 73", LC_OWN, KM_ST_EXCEPTION, NULL, false},
    {"0x7F super ok", 0, NULL, "F9 FF FD 03 7F 01 7F", LC_VALUE, 0, "F9 F5 01 04 7F 01 00 7A", false},
    {"0x7F broadcast", 0, NULL, "F9 FF FE 03 7F 01 7E", LC_NONE, 0, NULL, false},
    {"write level 0 ok", 0, NULL, "F9 FF 01 05 03 13 F4 01 EE", LC_NONE, 0, NULL, false},
    {"write level 0 failed", 0, NULL, "F9 FF 01 05 03 13 E9 03 F7", LC_NONE, KM_ST_FAILED, NULL, false},
    {"write level 1 ok", 1, NULL, "F9 FF 01 05 03 13 F4 01 EE", LC_OWN, 0, NULL, false},
    {"write level 1 failed", 1, NULL, "F9 FF 01 05 03 13 E9 03 F7", LC_OWN, KM_ST_FAILED, NULL, false},
    {"write level 1 reserved address", 1, NULL, "F9 FF 01 04 03 0D 00 EA", LC_OWN, KM_ST_EXCEPTION, NULL,
     false},
    {"write broadcast ok", 1, NULL, "F9 FF FE 05 03 13 F4 01 F1", LC_NONE, 0, NULL, false},
    {"write broadcast failed", 1, NULL, "F9 FF FE 05 03 13 E9 03 FA", LC_NONE, KM_ST_FAILED, NULL, false},
    {"0x04 ok", 1, NULL, "F9 FF 01 04 04 64 02 90", LC_NONE, 0, NULL, false},
    {"0x04 bad address", 1, NULL, "F9 FF 01 04 04 20 01 D5", LC_NONE, KM_ST_EXCEPTION, NULL, false},
    {"0x84 empty", 1, NULL, "F9 FF FE 02 84 7B", LC_NONE, 0, NULL, false},
    {"0x84 own ID, failing write", 1, "F9 FF 01 05 04 13 E9 03 F6", "F9 FF 01 02 84 78", LC_NONE,
     KM_ST_FAILED, NULL, false},
    {"0x84 broadcast, failing write", 1, "F9 FF 01 05 04 13 E9 03 F6", "F9 FF FE 02 84 7B", LC_NONE,
     KM_ST_FAILED, NULL, false},
    {"0x83 listing us", 1, NULL, "F9 FF FE 06 83 64 01 01 02 10", LC_NONE, 0, NULL, false},
    {"0x83 listing us, bad value", 1, NULL, "F9 FF FE 06 83 64 01 01 07 0B", LC_NONE, KM_ST_FAILED, NULL,
     false},
    {"0x83 not listing us", 1, NULL, "F9 FF FE 06 83 64 01 02 02 0F", LC_IGNORED, 0, NULL, false},
    {"0x83 unsupported address", 1, NULL, "F9 FF FE 06 83 13 01 01 05 5E", LC_NONE, KM_ST_EXCEPTION, NULL,
     false},
    {"0x83 malformed k", 1, NULL, "F9 FF FE 07 83 64 02 01 02 00 0E", LC_NONE, KM_ST_FAILED, NULL, false},
    {"0x83 to own ID", 1, NULL, "F9 FF 01 06 83 64 01 01 02 0D", LC_NONE, KM_ST_EXCEPTION, NULL, false},
    {"0x82 listing us", 0, NULL, "F9 FF FE 04 82 13 01 67", LC_VALUE, 0, "F9 F5 01 05 02 13 E8 03 F9", false},
    {"0x82 listing us, 0x01", 0, NULL, "F9 FF FE 04 82 01 01 79", LC_ALL, 0, NULL, true},
    {"0x82 listing us, reserved address", 0, NULL, "F9 FF FE 04 82 0D 01 6D", LC_OWN, KM_ST_EXCEPTION, NULL,
     false},
    {"0x82 not listing us", 0, NULL, "F9 FF FE 04 82 13 02 66", LC_IGNORED, 0, NULL, false},
    {"0x82 not listing us, reserved address", 0, NULL, "F9 FF FE 04 82 0D 02 6C", LC_NONE, KM_ST_EXCEPTION,
     NULL, false},
    {"0x82 no IDs", 0, NULL, "F9 FF FE 03 82 13 69", LC_NONE, KM_ST_EXCEPTION, NULL, false},
    {"0x82 to own ID", 0, NULL, "F9 FF 01 04 82 13 01 64", LC_NONE, KM_ST_EXCEPTION, NULL, false},
    {"0x82 to super ID", 0, NULL, "F9 FF FD 04 82 13 01 68", LC_IGNORED, 0, NULL, false},
    {"unknown command 0x78", 1, NULL, "F9 FF 01 03 78 13 70", LC_NONE, KM_ST_EXCEPTION, NULL, false},
    {"super-ID write", 1, NULL, "F9 FF FD 05 03 13 F4 01 F2", LC_IGNORED, 0, NULL, false},
};

/* The unreported state each case starts from. */
typedef enum { PRIOR_NONE, PRIOR_FAILED_WRITE, PRIOR_CHECKSUM } lc_prior_t;

static uint8_t lc_setup(const lc_case_t *c, lc_prior_t prior)
{
    kt_init(&fx, kt_product_pot(), LC_ID); /* response level 0 (0x11 = 0x02) */
    uint8_t bits = 0;
    if (prior == PRIOR_FAILED_WRITE) {
        kt_send_hex(&fx, "F9 FF 01 05 03 13 E9 03 F7"); /* 1001: out of range, level 0 */
        kt_no_reply(&fx);
        bits = KM_ST_FAILED;
    } else if (prior == PRIOR_CHECKSUM) {
        km_servo_note_checksum_error(&fx.s);
        bits = KM_ST_EXCEPTION;
    }
    if (c->level == 1) {
        kt_send_hex(&fx, "F9 FF 01 04 03 11 0A DC"); /* answers for itself: 0 */
        kt_reply_is_hex(&fx, "F9 F5 01 02 00 FC");
    }
    if (c->pre) {
        kt_send_hex(&fx, c->pre);
        kt_no_reply(&fx);
    }
    assert_int_equal(km_servo_status(&fx.s), bits);
    return bits;
}

/* Every command kind against every starting state: (a) the status byte of
 * its own answer, (b) what the next ping answers, (c) a second ping
 * answers 0 -- each exactly as the rule says. */
static void test_s4_status_life_cycle_every_command_kind(void **state)
{
    (void)state;
    static const lc_prior_t priors[] = {PRIOR_NONE, PRIOR_FAILED_WRITE, PRIOR_CHECKSUM};
    for (unsigned i = 0; i < sizeof lc_cases / sizeof lc_cases[0]; i++) {
        const lc_case_t *c = &lc_cases[i];
        for (unsigned p = 0; p < 3; p++) {
            const uint8_t prior = lc_setup(c, priors[p]);
            kt_send_hex(&fx, c->frame);
            uint8_t next_ping = prior;
            switch (c->kind) {
            case LC_ALL:
                if (c->read01) {
                    if (fx.reply.len != 9 || fx.reply.bytes[4] != 0x02 || fx.reply.bytes[5] != 0x01 ||
                        fx.reply.bytes[6] != (prior | c->own)) {
                        fail_msg("%s, prior 0x%02X: 0x01 answers status 0x%02X", c->name, prior,
                                 fx.reply.len == 9 ? fx.reply.bytes[6] : 0xFFu);
                    }
                } else {
                    if (fx.reply.len != 6 || fx.reply.bytes[4] != (prior | c->own)) {
                        fail_msg("%s, prior 0x%02X: answers 0x%02X, want 0x%02X", c->name, prior,
                                 fx.reply.len == 6 ? fx.reply.bytes[4] : 0xFFu, prior | c->own);
                    }
                    kt_reply_is_status(&fx, LC_ID, (uint8_t)(prior | c->own));
                }
                next_ping = 0;
                break;
            case LC_OWN:
                if (fx.reply.len != 6 || fx.reply.bytes[4] != c->own) {
                    fail_msg("%s, prior 0x%02X: answers 0x%02X, want 0x%02X", c->name, prior,
                             fx.reply.len == 6 ? fx.reply.bytes[4] : 0xFFu, c->own);
                }
                kt_reply_is_status(&fx, LC_ID, c->own);
                break;
            case LC_VALUE:
                kt_reply_is_hex(&fx, c->answer);
                break;
            case LC_NONE:
                if (fx.reply.len != 0) {
                    fail_msg("%s answered", c->name);
                }
                next_ping = (uint8_t)(prior | c->own);
                break;
            case LC_IGNORED:
                assert_int_equal(c->own, 0);
                kt_no_reply(&fx);
                break;
            }
            if (km_servo_status(&fx.s) != next_ping) {
                fail_msg("%s, prior 0x%02X: km_servo_status 0x%02X, want 0x%02X", c->name, prior,
                         km_servo_status(&fx.s), next_ping);
            }
            kt_send_hex(&fx, PING_1);
            if (fx.reply.len != 6 || fx.reply.bytes[4] != next_ping) {
                fail_msg("%s, prior 0x%02X: next ping 0x%02X, want 0x%02X", c->name, prior,
                         fx.reply.len == 6 ? fx.reply.bytes[4] : 0xFFu, next_ping);
            }
            kt_reply_is_status(&fx, LC_ID, next_ping);
            kt_send_hex(&fx, PING_1);
            kt_reply_is_hex(&fx, "F9 F5 01 02 00 FC");
        }
    }
}

/* Rule 6: the super-ID write and the 0x83 that does not list us really are
 * ignored (nothing else changes either); the ones that run did run. */
static void test_s4_life_cycle_cases_take_effect(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), LC_ID);
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_send_hex(&fx, "F9 FF FD 05 03 13 F4 01 F2");
    kt_send_hex(&fx, "F9 FF FE 06 83 64 01 02 02 0F");
    kt_assert_unchanged(&fx, &sn);
    kt_send_hex(&fx, "F9 FF 01 05 03 13 F4 01 EE");
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_MAX_TORQUE), 500);
    kt_send_hex(&fx, "F9 FF FE 06 83 64 01 01 02 10");
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_SWITCH), 2);
}

/* The audit's sequence (a), at response level 1: a checksum error, then a
 * good write. The write answers 00 (its own outcome); the next ping answers
 * 20 (the checksum error, unreported until then); the one after, 00. */
static void test_s4_audit_checksum_error_then_good_write_level1(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 0);
    kt_send_hex(&fx, "F9 FF 00 04 03 11 0A DD"); /* response level 1 */
    kt_reply_is_hex(&fx, "F9 F5 00 02 00 FD");
    km_servo_note_checksum_error(&fx.s);
    kt_send_hex(&fx, "F9 FF 00 05 03 13 E8 03 F9");
    kt_reply_is_hex(&fx, "F9 F5 00 02 00 FD");
    kt_send_hex(&fx, "F9 FF 00 02 01 FC");
    kt_reply_is_hex(&fx, "F9 F5 00 02 20 DD");
    kt_send_hex(&fx, "F9 FF 00 02 01 FC");
    kt_reply_is_hex(&fx, "F9 F5 00 02 00 FD");
}

/* The audit's sequence (b), at response level 0: a failed write (1001),
 * then a read of 0x13, answered normally with the value unchanged, then a
 * ping answers 40: the read's answer has no status byte and hid nothing. */
static void test_s4_audit_failed_write_then_read_then_ping_level0(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 0);
    kt_send_hex(&fx, "F9 FF 00 05 03 13 E9 03 F8");
    kt_no_reply(&fx);
    kt_send_hex(&fx, "F9 FF 00 03 02 13 E7");
    kt_reply_is_hex(&fx, "F9 F5 00 05 02 13 E8 03 FA");
    kt_send_hex(&fx, "F9 FF 00 02 01 FC");
    kt_reply_is_hex(&fx, "F9 F5 00 02 40 BD");
    kt_send_hex(&fx, "F9 FF 00 02 01 FC");
    kt_reply_is_hex(&fx, "F9 F5 00 02 00 FD");
}

/* Rule 5 with "Malformed frames": a broadcast read or extension read is
 * executed but not answered, so its own outcome -- bit 5 for an address
 * this servo does not have -- waits for the next ping. */
static void test_s4_broadcast_read_bad_address_reported_by_next_ping(void **state)
{
    (void)state;
    static const char *frames[] = {
        "F9 FF FE 03 02 20 DC", /* read of reserved 0x20 */
        "F9 FF FE 03 7F 09 76", /* extension read of an address 0x7F does not have */
    };
    for (unsigned i = 0; i < 2; i++) {
        kt_init(&fx, kt_product_pot(), LC_ID);
        kt_send_hex(&fx, frames[i]);
        kt_no_reply(&fx);
        kt_send_hex(&fx, PING_1);
        if (fx.reply.len != 6 || fx.reply.bytes[4] != KM_ST_EXCEPTION) {
            fail_msg("%s: next ping answers 0x%02X, want 0x20", frames[i],
                     fx.reply.len == 6 ? fx.reply.bytes[4] : 0xFFu);
        }
        kt_send_hex(&fx, PING_1);
        kt_reply_is_hex(&fx, "F9 F5 01 02 00 FC");
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s4_bit6_reported_by_next_ping),
        cmocka_unit_test(test_s4_bit6_kept_through_broadcast_write),
        cmocka_unit_test(test_s4_super_ping_and_0x01_report_other_super_reads_keep),
        cmocka_unit_test(test_s4_super_write_ignored_bits_stay),
        cmocka_unit_test(test_s4_bit5_set_and_reported_once),
        cmocka_unit_test(test_s4_own_answer_carries_own_bits_only),
        cmocka_unit_test(test_s4_status_life_cycle_every_command_kind),
        cmocka_unit_test(test_s4_life_cycle_cases_take_effect),
        cmocka_unit_test(test_s4_audit_checksum_error_then_good_write_level1),
        cmocka_unit_test(test_s4_audit_failed_write_then_read_then_ping_level0),
        cmocka_unit_test(test_s4_broadcast_read_bad_address_reported_by_next_ping),
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
