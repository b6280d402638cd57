/* SPDX-License-Identifier: Apache-2.0 */
/* Multi-ID read 0x82 (docs/protocol.md §3 and §7 leave it "to be completed"; this
 * firmware's definition: docs/protocol-decisions.md "Multi-ID read 0x82"):
 * the worked frames, the slot each listed servo answers in, and every bad
 * input's outcome, on a few servos side by side. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_test_support.h"

#define NSERVO 4
static kt_fx_t bus[NSERVO]; /* bus[i] has ID i */
static kt_fx_t twin;

static void init_bus(const km_product_t *p)
{
    for (uint8_t i = 0; i < NSERVO; i++) {
        kt_init(&bus[i], p, i);
    }
}

static void set_position(kt_fx_t *fx, int32_t pos)
{
    km_live_t live = {0};
    live.position = pos;
    km_servo_set_live(&fx->s, &live);
}

/* Every servo of bus[] gets the frame (as on a wire). */
static void send_all_hex(const char *hex)
{
    for (uint8_t i = 0; i < NSERVO; i++) {
        kt_send_hex(&bus[i], hex);
    }
}

static void send_all(uint8_t id, const uint8_t *body, unsigned n)
{
    for (uint8_t i = 0; i < NSERVO; i++) {
        kt_send(&bus[i], id, 0x82, body, n);
    }
}

/* "Multi-ID read 0x82", worked frame: 0x46 from servos 3, 1, 2 in that
 * order. Each answers its 0x02 answer, in the slot of its list position
 * (not of its ID): 200, 200 + 1129, 200 + 2 x 1129 us at 115200 baud. */
static void test_mread_worked_frame(void **state)
{
    (void)state;
    init_bus(kt_product_pot());
    set_position(&bus[3], 900);
    set_position(&bus[1], -200);
    set_position(&bus[2], 450);
    send_all_hex("F9 FF FE 06 82 46 03 01 02 2D");
    kt_no_reply(&bus[0]);
    kt_reply_is_hex(&bus[3], "F9 F5 03 05 02 46 84 03 28");
    kt_reply_is_hex(&bus[1], "F9 F5 01 05 02 46 38 FF 7A");
    kt_reply_is_hex(&bus[2], "F9 F5 02 05 02 46 C2 01 ED");
    assert_int_equal(kt_slot_us(11, 115200), 1129);
    assert_int_equal(bus[3].reply.delay_us, 200u);
    assert_int_equal(bus[1].reply.delay_us, 200u + 1129u);
    assert_int_equal(bus[2].reply.delay_us, 200u + 2u * 1129u);
    for (uint8_t i = 0; i < NSERVO; i++) {
        assert_int_equal(km_servo_status(&bus[i].s), 0);
        kt_ping_is(&bus[i], i, 0);
    }
}

/* The answer is exactly what a 0x02 read of the address answers, for every
 * readable register (a twin servo in the same state reads it with 0x02),
 * on both products; the slot is that read's longest answer + 2 bytes. */
static void test_mread_answer_is_the_read_answer(void **state)
{
    (void)state;
    const km_product_t *products[] = {kt_product_pot(), kt_product_enc()};
    for (unsigned p = 0; p < 2; p++) {
        for (unsigned r = 0; r < KM_REG_COUNT; r++) {
            if (!(km_reg_table[r].access & KM_R)) {
                continue;
            }
            const uint8_t addr = km_reg_table[r].addr;
            kt_init(&bus[2], products[p], 2);
            kt_init(&twin, products[p], 2);
            const uint8_t body[] = {addr, 7, 2};
            kt_send(&bus[2], KM_ID_BROADCAST, 0x82, body, sizeof body);
            kt_read(&twin, 2, addr);
            assert_int_equal(bus[2].reply.len, twin.reply.len);
            assert_memory_equal(bus[2].reply.bytes, twin.reply.bytes, twin.reply.len);
            assert_true(twin.reply.len > 6u); /* a value, not an error */
            /* the longest answer: value size + 7 (0x0A: 16 B of text) */
            const unsigned longest = addr == 0x0A                     ? 23u
                                     : (addr == 0x46 || addr == 0x4C) ? 11u
                                                                      : twin.reply.len;
            assert_int_equal(bus[2].reply.delay_us, 200u + kt_slot_us(longest, 115200));
        }
    }
}

/* Slots follow the active baud and 0x12: 0x0A (16 B text, 25 byte times per
 * slot) at 1 Mbit/s with a delay of 500 us; 0x13 (u16) at 9600. */
static void test_mread_slots_baud_and_delay(void **state)
{
    (void)state;
    kt_init(&bus[1], kt_product_pot(), 1);
    kt_write_u16(&bus[1], 1, 0x12, 500);
    km_servo_set_active_baud(&bus[1].s, 1000000u);
    const uint8_t body[] = {0x0A, 9, 8, 7, 1};
    kt_send(&bus[1], KM_ID_BROADCAST, 0x82, body, sizeof body);
    assert_int_equal(kt_slot_us(23, 1000000), 250);
    assert_int_equal(bus[1].reply.delay_us, 500u + 3u * 250u);
    kt_init(&bus[1], kt_product_pot(), 1);
    km_servo_set_active_baud(&bus[1].s, 9600u);
    const uint8_t b13[] = {0x13, 0, 1};
    kt_send(&bus[1], KM_ID_BROADCAST, 0x82, b13, sizeof b13);
    assert_int_equal(kt_slot_us(9, 9600), 11459); /* 110 bits: 11458.3 us */
    assert_int_equal(bus[1].reply.delay_us, 200u + 11459u);
}

/* The longest list the frame allows: length 252 = address + 249 IDs. The
 * servo listed last answers in slot 248. (A longer list needs a length above
 * 252: no frame, tests/unit/app/test_app_multi_read.c sends its bytes.) */
static void test_mread_longest_list(void **state)
{
    (void)state;
    kt_init(&bus[0], kt_product_pot(), 0);
    uint8_t body[KM_BODY_MAX];
    body[0] = 0x46;
    for (unsigned j = 0; j < 249u; j++) {
        body[1 + j] = (uint8_t)(j + 1u); /* 1..249, then 0 last */
    }
    body[249] = 0;
    kt_send(&bus[0], KM_ID_BROADCAST, 0x82, body, 250);
    kt_reply_is_hex(&bus[0], "F9 F5 00 05 02 46 00 00 B2");
    assert_int_equal(bus[0].reply.delay_us, 200u + 248u * 1129u);
}

/* "Answer slots on emulated buses": a slot floor lengthens every slot
 * shorter than it, super ID and 0x82 alike, and leaves longer slots and
 * the own-ID answer alone; it is capped at KM_SLOT_FLOOR_MAX_US. */
static void test_mread_and_super_slot_floor(void **state)
{
    (void)state;
    kt_init(&bus[3], kt_product_pot(), 3);
    km_servo_set_slot_floor_us(&bus[3].s, 3000u);
    const uint8_t body[] = {0x46, 1, 2, 3};
    kt_send(&bus[3], KM_ID_BROADCAST, 0x82, body, sizeof body);
    assert_int_equal(bus[3].reply.delay_us, 200u + 2u * 3000u);
    kt_ping(&bus[3], KM_ID_SUPER);
    assert_int_equal(bus[3].reply.delay_us, 200u + 3u * 3000u);
    kt_read(&bus[3], KM_ID_SUPER, 0x46);
    assert_int_equal(bus[3].reply.delay_us, 200u + 3u * 3000u);
    kt_read(&bus[3], 3, 0x46);
    assert_int_equal(bus[3].reply.delay_us, 200u); /* own ID: no slot */
    km_servo_set_active_baud(&bus[3].s, 9600u);    /* 0x0A: 26042 us, above the floor */
    kt_read(&bus[3], KM_ID_SUPER, 0x0A);
    assert_int_equal(bus[3].reply.delay_us, 200u + 3u * kt_slot_us(23, 9600));
    km_servo_set_slot_floor_us(&bus[3].s, 0xFFFFFFFFu);
    kt_ping(&bus[3], KM_ID_SUPER);
    assert_int_equal(bus[3].reply.delay_us, 200u + 3u * KM_SLOT_FLOOR_MAX_US);
    km_servo_set_slot_floor_us(&bus[3].s, 0u); /* 0: the rule alone */
    kt_ping(&bus[3], KM_ID_SUPER);
    assert_int_equal(bus[3].reply.delay_us, 200u + 3u * kt_slot_us(6, 9600));
}

/* Every position in lists of 1..13 IDs (the scan takes four IDs a pass,
 * then the rest: every split of the list), and the same lists without it. */
static void test_mread_every_position(void **state)
{
    (void)state;
    kt_init(&bus[0], kt_product_pot(), 0);
    for (unsigned n = 1; n <= 13u; n++) {
        for (unsigned j = 0; j <= n; j++) { /* j == n: not listed */
            uint8_t body[14];
            body[0] = 0x13;
            for (unsigned k = 0; k < n; k++) {
                body[1 + k] = k == j ? 0u : (uint8_t)(k + 1u);
            }
            kt_send(&bus[0], KM_ID_BROADCAST, 0x82, body, 1u + n);
            if (j == n) {
                kt_no_reply(&bus[0]);
            } else {
                assert_int_equal(bus[0].reply.len, 9);
                assert_int_equal(bus[0].reply.delay_us, 200u + j * kt_slot_us(9, 115200));
            }
        }
    }
}

/* An ID listed twice answers once, in the slot of its first position; the
 * later slot stays silent. IDs no servo can have (251..255) hold a slot
 * that stays silent and shift the servos after them. */
static void test_mread_duplicates_and_unusable_ids(void **state)
{
    (void)state;
    init_bus(kt_product_pot());
    const uint8_t body[] = {0x46, 0xFD, 2, 0xFE, 2, 251, 3, 0xFF, 1};
    send_all(KM_ID_BROADCAST, body, sizeof body);
    kt_no_reply(&bus[0]);
    assert_int_equal(bus[2].reply.len, 9);
    assert_int_equal(bus[2].reply.delay_us, 200u + 1u * 1129u);
    assert_int_equal(bus[3].reply.delay_us, 200u + 5u * 1129u);
    assert_int_equal(bus[1].reply.delay_us, 200u + 7u * 1129u);
    for (uint8_t i = 0; i < NSERVO; i++) {
        kt_ping_is(&bus[i], i, 0);
    }
}

/* Own ID absent: no answer and nothing changes, not even the 0x04 buffer
 * or bits waiting for a ping. */
static void test_mread_not_listed_changes_nothing(void **state)
{
    (void)state;
    kt_init(&bus[0], kt_product_pot(), 0);
    kt_write_u8(&bus[0], 0, 0x64, 9); /* bit 6 waits for a ping */
    const uint8_t sync[] = {0x64, 0x02};
    kt_send(&bus[0], 0, 0x04, sync, sizeof sync);
    kt_snap_t sn;
    kt_snap(&bus[0], &sn);
    const uint8_t body[] = {0x46, 1, 2, 3};
    kt_send(&bus[0], KM_ID_BROADCAST, 0x82, body, sizeof body);
    kt_no_reply(&bus[0]);
    kt_assert_unchanged(&bus[0], &sn);
    kt_send_hex(&bus[0], "F9 FF FE 02 84 7B"); /* the buffer still runs */
    assert_int_equal(bus[0].fake.n_requests, 1);
    kt_ping_is(&bus[0], 0, KM_ST_FAILED);
}

/* A listed servo: it was addressed, so its 0x04 buffer is cleared (§3);
 * the unlisted one keeps its buffer. */
static void test_mread_clears_sync_buffer_of_listed_only(void **state)
{
    (void)state;
    init_bus(kt_product_pot());
    const uint8_t sync[] = {0x64, 0x02};
    kt_send(&bus[1], 1, 0x04, sync, sizeof sync);
    kt_send(&bus[2], 2, 0x04, sync, sizeof sync);
    const uint8_t body[] = {0x13, 1};
    kt_send(&bus[1], KM_ID_BROADCAST, 0x82, body, sizeof body);
    kt_send(&bus[2], KM_ID_BROADCAST, 0x82, body, sizeof body);
    assert_false(bus[1].s.sync.full);
    assert_true(bus[2].s.sync.full);
}

/* "Status bits 5 and 6": the answer is a read answer. 0x01 reports the bits
 * waiting for a ping and clears them; another address leaves them. */
static void test_mread_status_bits_as_a_read(void **state)
{
    (void)state;
    kt_init_seed(&bus[2], kt_product_pot(), 2, 99u);
    kt_init_seed(&twin, kt_product_pot(), 2, 99u);
    km_servo_note_checksum_error(&bus[2].s);
    km_servo_note_checksum_error(&twin.s);
    const uint8_t b13[] = {0x13, 2};
    kt_send(&bus[2], KM_ID_BROADCAST, 0x82, b13, sizeof b13);
    const uint8_t v13[] = {0xE8, 0x03};
    kt_reply_is_read(&bus[2], 2, 0x13, v13, 2);
    assert_int_equal(km_servo_status(&bus[2].s), KM_ST_EXCEPTION); /* still waiting */
    kt_send_hex(&bus[2], "F9 FF FE 04 82 01 02 78");
    kt_read(&twin, 2, 0x01); /* the same answer, random byte included */
    assert_int_equal(bus[2].reply.bytes[6], KM_ST_EXCEPTION);
    assert_int_equal(bus[2].reply.len, twin.reply.len);
    assert_memory_equal(bus[2].reply.bytes, twin.reply.bytes, twin.reply.len);
    kt_ping_is(&bus[2], 2, 0); /* carried once */
}

/* Response level (0x11 bit 3) rules writes only: 0x82 answers at 0 and 1. */
static void test_mread_response_level(void **state)
{
    (void)state;
    for (uint8_t level = 0; level < 2; level++) {
        kt_init(&bus[1], kt_product_pot(), 1);
        kt_write_u8(&bus[1], 1, 0x11, level ? 0x08 : 0x00);
        const uint8_t body[] = {0x13, 1};
        kt_send(&bus[1], KM_ID_BROADCAST, 0x82, body, sizeof body);
        const uint8_t v13[] = {0xE8, 0x03};
        kt_reply_is_read(&bus[1], 1, 0x13, v13, 2);
        assert_int_equal(bus[1].reply.delay_us, 200u);
    }
}

/* Unknown or write-only address (0x0D reserved, 0x02 restart): every servo
 * judges it, bit 5 (§4, as for 0x83). A listed servo answers what a 0x02
 * read answers, the short response with bit 5, in its slot cut for the
 * short response (6 bytes); an unlisted one keeps bit 5 for the next ping
 * and its 0x04 buffer is cleared. Nothing runs (no restart). */
static void test_mread_unreadable_address_bit5(void **state)
{
    (void)state;
    static const uint8_t addrs[] = {0x0D, 0x02, 0x00, 0xFF};
    for (unsigned a = 0; a < sizeof addrs; a++) {
        init_bus(kt_product_pot());
        const uint8_t sync[] = {0x64, 0x02};
        kt_send(&bus[0], 0, 0x04, sync, sizeof sync);
        const uint8_t body[] = {addrs[a], 3, 1};
        send_all(KM_ID_BROADCAST, body, sizeof body);
        kt_reply_is_status(&bus[3], 3, KM_ST_EXCEPTION);
        kt_reply_is_status(&bus[1], 1, KM_ST_EXCEPTION);
        assert_int_equal(bus[3].reply.delay_us, 200u);
        assert_int_equal(bus[1].reply.delay_us, 200u + kt_slot_us(6, 115200));
        kt_no_reply(&bus[0]);
        kt_no_reply(&bus[2]);
        assert_false(bus[0].s.sync.full);
        for (uint8_t i = 0; i < NSERVO; i++) {
            assert_int_equal(bus[i].fake.restarts, 0);
            assert_int_equal(bus[i].fake.n_requests, 0);
            /* answered servos carried it; the others report it once */
            kt_ping_is(&bus[i], i, i == 1 || i == 3 ? 0 : KM_ST_EXCEPTION);
            kt_ping_is(&bus[i], i, 0);
        }
    }
}

/* No address, or an address and no ID: malformed, bit 5 on every servo for
 * the next ping, the 0x04 buffer cleared, no answer, nothing else changes. */
static void test_mread_no_address_or_no_ids(void **state)
{
    (void)state;
    static const char *frames[] = {"F9 FF FE 02 82 7D", "F9 FF FE 03 82 46 36"};
    for (unsigned k = 0; k < 2; k++) {
        init_bus(kt_product_pot());
        const uint8_t sync[] = {0x64, 0x02};
        kt_send(&bus[2], 2, 0x04, sync, sizeof sync);
        kt_snap_t sn;
        kt_snap(&bus[2], &sn);
        send_all_hex(frames[k]);
        sn.unreported |= KM_ST_EXCEPTION;
        sn.sync_full = false;
        kt_assert_unchanged(&bus[2], &sn);
        for (uint8_t i = 0; i < NSERVO; i++) {
            kt_no_reply(&bus[i]);
            kt_ping_is(&bus[i], i, KM_ST_EXCEPTION);
            kt_ping_is(&bus[i], i, 0);
        }
    }
}

/* Not broadcast: to the own ID, bit 5 for the next ping, the 0x04 buffer
 * cleared, no answer (as 0x83); to the super ID or another servo's ID,
 * ignored: nothing changes at all. */
static void test_mread_not_broadcast(void **state)
{
    (void)state;
    kt_init(&bus[1], kt_product_pot(), 1);
    const uint8_t sync[] = {0x64, 0x02};
    kt_send(&bus[1], 1, 0x04, sync, sizeof sync);
    kt_write_u8(&bus[1], 1, 0x64, 9); /* bit 6 pending; clears the buffer */
    kt_send(&bus[1], 1, 0x04, sync, sizeof sync);
    kt_snap_t sn;
    kt_snap(&bus[1], &sn);
    const uint8_t body[] = {0x46, 1, 2};
    kt_send(&bus[1], KM_ID_SUPER, 0x82, body, sizeof body);
    kt_no_reply(&bus[1]);
    kt_send(&bus[1], 2, 0x82, body, sizeof body);
    kt_no_reply(&bus[1]);
    kt_assert_unchanged(&bus[1], &sn);
    kt_send(&bus[1], 1, 0x82, body, sizeof body);
    kt_no_reply(&bus[1]);
    sn.unreported |= KM_ST_EXCEPTION;
    sn.sync_full = false;
    kt_assert_unchanged(&bus[1], &sn);
    kt_ping_is(&bus[1], 1, KM_ST_EXCEPTION | KM_ST_FAILED);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mread_worked_frame),
        cmocka_unit_test(test_mread_answer_is_the_read_answer),
        cmocka_unit_test(test_mread_slots_baud_and_delay),
        cmocka_unit_test(test_mread_longest_list),
        cmocka_unit_test(test_mread_and_super_slot_floor),
        cmocka_unit_test(test_mread_every_position),
        cmocka_unit_test(test_mread_duplicates_and_unusable_ids),
        cmocka_unit_test(test_mread_not_listed_changes_nothing),
        cmocka_unit_test(test_mread_clears_sync_buffer_of_listed_only),
        cmocka_unit_test(test_mread_status_bits_as_a_read),
        cmocka_unit_test(test_mread_response_level),
        cmocka_unit_test(test_mread_unreadable_address_bit5),
        cmocka_unit_test(test_mread_no_address_or_no_ids),
        cmocka_unit_test(test_mread_not_broadcast),
    };
    return cmocka_run_group_tests_name("dispatch_multi_read", tests, NULL, NULL);
}
