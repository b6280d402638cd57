/* SPDX-License-Identifier: Apache-2.0 */
/* docs/protocol.md §3 commands and the §5 registers whose write or read is more
 * than storing a value: identity, ID and baud change, restart, user data
 * reset, torque switch, control mode, zero offsets, protections, live state,
 * encoder-only commands and store failures. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_test_support.h"

#define ID 7
static kt_fx_t fx;

static void answering(void)
{
    kt_write_u8(&fx, ID, 0x11, 0x0A);
    kt_reply_is_status(&fx, ID, 0);
}

static void move_time(uint8_t id)
{
    const uint8_t mv[] = {0x84, 0x03, 0xE8, 0x03};
    kt_write(&fx, id, 0x65, mv, 4);
}

static void motor_torque(uint8_t id, int16_t pwm)
{
    kt_write_u16(&fx, id, 0x6E, (uint16_t)pwm);
}

/* §5.1 0x01: [status][random]: the status of this read, random from xorshift32. */
static void test_s5_1_0x01_status_read(void **state)
{
    (void)state;
    kt_init_seed(&fx, kt_product_pot(), ID, 0xC0FFEEu);
    km_live_t live = {0};
    live.running = true;
    live.protections = 0x02;
    km_servo_set_live(&fx.s, &live);
    kt_write_u8(&fx, ID, 0x64, 9); /* bit 6: the status read reports it, then clears it */
    kt_read(&fx, ID, 0x01);
    const uint32_t r1 = kt_xorshift32(0xC0FFEEu);
    const uint8_t want[2] = {0xC2, (uint8_t)r1};
    kt_reply_is_read(&fx, ID, 0x01, want, 2);
    kt_read(&fx, ID, 0x01);
    const uint8_t want2[2] = {0x82, (uint8_t)kt_xorshift32(r1)};
    kt_reply_is_read(&fx, ID, 0x01, want2, 2);
}

/* §5.1 0x0A: model name as ASCII, up to 16 B (Decision). */
static void test_s5_1_0x0A_model_text(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_read(&fx, ID, 0x0A);
    const char *m = "KM-TEST-POT";
    kt_reply_is_read(&fx, ID, 0x0A, (const uint8_t *)m, (unsigned)strlen(m));
    kt_init(&fx, kt_product_enc(), ID);
    kt_read(&fx, ID, 0x0A);
    kt_reply_is_read(&fx, ID, 0x0A, (const uint8_t *)"KM-TEST-ENCODER-", 16);
}

/* §5.1 0x0B = 0x05020000, little-endian on the wire. */
static void test_s5_1_0x0B_protocol_version(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_read(&fx, ID, 0x0B);
    const uint8_t want[] = {0x00, 0x00, 0x02, 0x05};
    kt_reply_is_read(&fx, ID, 0x0B, want, 4);
}

/* §5.1 0x0C from the product config. */
static void test_s5_1_0x0C_firmware_version(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_read(&fx, ID, 0x0C);
    const uint8_t want[] = {0x02, 0x10, 0x11, 0x52}; /* 0x52111002 LE */
    kt_reply_is_read(&fx, ID, 0x0C, want, 4);
    kt_init(&fx, kt_product_enc(), ID);
    kt_read(&fx, ID, 0x0C);
    const uint8_t want2[] = {0x03, 0x10, 0x20, 0x00};
    kt_reply_is_read(&fx, ID, 0x0C, want2, 4);
}

/* §3 ID change: committed before it applies, answered with the old ID, the
 * new ID applies right after. */
static void test_s5_1_0x0F_id_change(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    answering();
    const unsigned c0 = fx.fake.n_commits;
    kt_write_u8(&fx, ID, 0x0F, 42);
    kt_reply_is_status(&fx, ID, 0);
    assert_int_equal(fx.fake.n_commits, c0 + 1);
    assert_int_equal(fx.fake.commits[c0].n, 1);
    assert_int_equal(kt_commit_value(&fx.fake.commits[c0], 0x0F), 42);
    kt_ping(&fx, ID);
    kt_no_reply(&fx);
    kt_ping(&fx, 42);
    kt_reply_is_status(&fx, 42, 0);
    kt_read(&fx, 42, 0x0F);
    const uint8_t v = 42;
    kt_reply_is_read(&fx, 42, 0x0F, &v, 1);
}

/* ID change whose commit fails: bit 6, the old ID stays. At response
 * level 1 the write's own answer carried the bit 6 ("One life cycle for
 * bits 5 and 6", rule 4), so the next ping has nothing left to report. */
static void test_s5_1_0x0F_id_change_commit_fails(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    answering();
    fx.fake.fail_next_commit = true;
    kt_write_u8(&fx, ID, 0x0F, 42);
    kt_reply_is_status(&fx, ID, KM_ST_FAILED);
    assert_int_equal(fx.fake.n_commits, 2); /* 0x11, then the refused 0x0F */
    assert_false(fx.fake.commits[1].accepted);
    kt_ping(&fx, 42);
    kt_no_reply(&fx);
    kt_ping_is(&fx, ID, 0);
    /* at level 0 the same failure waits for the next ping */
    kt_write_u8(&fx, ID, 0x11, 0x02);
    kt_no_reply(&fx); /* §3: the level after the write decides (test_s3_response_level) */
    fx.fake.fail_next_commit = true;
    kt_write_u8(&fx, ID, 0x0F, 42);
    kt_no_reply(&fx);
    assert_int_equal(km_servo_id(&fx.s), ID);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    kt_ping_is(&fx, ID, 0);
}

/* §3 baud change: stored and committed; the active baud is unchanged until
 * restart (a re-init from the store applies it). */
static void test_s5_1_0x10_baud_change(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_write_u16(&fx, ID, 0x10, 5000);
    assert_int_equal(fx.fake.n_commits, 1);
    assert_int_equal(kt_commit_value(&fx.fake.commits[0], 0x10), 5000);
    kt_read(&fx, ID, 0x10);
    assert_int_equal(kt_read_le(&fx, 0x10), 5000);
    assert_int_equal(km_servo_active_baud(&fx.s), 115200);
    kt_ping(&fx, KM_ID_SUPER);
    assert_int_equal(fx.reply.delay_us, 200 + ID * kt_slot_us(6, 115200));
    /* The restart: re-initialise from what was committed. */
    kt_persisted_set(&fx, 0x10, fx.fake.commits[0].values[0]);
    kt_reinit(&fx, kt_product_pot());
    assert_int_equal(km_servo_active_baud(&fx.s), 500000);
    kt_read(&fx, ID, 0x10);
    assert_int_equal(kt_read_le(&fx, 0x10), 5000);
    kt_ping(&fx, KM_ID_SUPER);
    assert_int_equal(fx.reply.delay_us, 200 + ID * kt_slot_us(6, 500000));
    assert_int_equal(kt_slot_us(6, 500000), 160); /* 80 bits at 500000 baud */
}

/* §3 restart via broadcast: restarts, no answer. */
static void test_s5_1_0x02_restart_broadcast(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t magic[] = {0xE1, 0xE2, 0xE3, 0xE4};
    kt_write(&fx, KM_ID_BROADCAST, 0x02, magic, 4);
    kt_no_reply(&fx);
    assert_int_equal(fx.fake.restarts, 1);
}

/* Expected defaults from docs/protocol.md §5 ("—" = the product's value). */
static uint32_t spec_default(uint8_t addr, const km_product_t *p)
{
    switch (addr) {
    case 0x0F:
        return 0;
    case 0x10:
        return 1152;
    case 0x11:
        return 0x02;
    case 0x12:
        return 200;
    case 0x13:
        return 1000;
    case 0x14:
        return p->max_current_ma;
    case 0x15:
        return p->max_speed_dps;
    case 0x16:
        return (uint16_t)p->zero_offset1;
    case 0x17:
        return 0;
    case 0x19:
        return (uint16_t)p->angle_min;
    case 0x1A:
        return (uint16_t)p->angle_max;
    case 0x32:
        return 0x0F;
    case 0x33:
        return 0x00;
    case 0x34:
        return 0x54;
    case 0x3C:
        return (uint32_t)p->voltage_high_v | ((uint32_t)p->voltage_low_v << 8);
    case 0x3D:
        return 60u | (5u << 8);
    case 0x3E:
        return (uint32_t)p->current_threshold_ma | (20u << 16);
    case 0x3F:
        return 600u | (20u << 16);
    default:
        fail_msg("no default for 0x%02X", addr);
        return 0;
    }
}

static const uint8_t persisted_addrs[] = {0x0F, 0x10, 0x11, 0x12, 0x13, 0x14, 0x15, 0x16, 0x17,
                                          0x19, 0x1A, 0x32, 0x33, 0x34, 0x3C, 0x3D, 0x3E, 0x3F};

/* A servo whose user data all differ from the defaults, 0x16 included
 * (factory calibration handed over by the store). */
static void init_changed(void)
{
    kt_init(&fx, kt_product_pot(), ID);
    static const struct {
        uint8_t addr;
        uint32_t v;
    } changed[] = {
        {0x10, 10000},
        {0x11, 0x0B},
        {0x12, 300},
        {0x13, 500},
        {0x14, 1000},
        {0x15, 300},
        {0x16, 99},
        {0x17, 55},
        {0x19, 0xFC18 /* -1000 */},
        {0x1A, 1000},
        {0x32, 0x03},
        {0x33, 0x01},
        {0x34, 0x00},
        {0x3C, 12u | (7u << 8)},
        {0x3D, 70u | (10u << 8)},
        {0x3E, 1000u | (5u << 16)},
        {0x3F, 500u | (5u << 16)},
    };
    unsigned k = 0;
    for (unsigned j = 0; j < KM_REG_COUNT; j++) {
        if (!km_reg_table[j].persisted)
            continue;
        for (unsigned c = 0; c < sizeof changed / sizeof changed[0]; c++) {
            if (changed[c].addr == km_reg_table[j].addr)
                fx.persisted[k] = changed[c].v;
        }
        k++;
    }
    km_servo_init(&fx.s, kt_product_pot(), fx.persisted, 1, &fx.ops);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_LIMIT), 500); /* mirrors from init */
}

static uint32_t reg_by_addr(uint8_t addr)
{
    const int r = km_reg_find(addr);
    assert_true(r >= 0);
    return km_servo_reg(&fx.s, (km_reg_index_t)r);
}

/* §5.1 0x03 level 1: everything back to defaults except ID, baud and the zero
 * offsets; one all-or-nothing commit; 0x5B..0x5D follow. */
static void test_s5_1_0x03_userdata_reset_level1(void **state)
{
    (void)state;
    init_changed();
    kt_write_u8(&fx, ID, 0x03, 1);
    assert_int_equal(fx.fake.n_commits, 1);
    const kt_commit_t *c = &fx.fake.commits[0];
    for (unsigned i = 0; i < sizeof persisted_addrs; i++) {
        const uint8_t a = persisted_addrs[i];
        const bool kept = a == 0x0F || a == 0x10 || a == 0x16 || a == 0x17;
        assert_int_equal(kt_commit_has(c, a), !kept);
        if (!kept) {
            assert_int_equal(kt_commit_value(c, a), spec_default(a, kt_product_pot()));
            assert_int_equal(reg_by_addr(a), spec_default(a, kt_product_pot()));
        }
    }
    assert_int_equal(c->n, sizeof persisted_addrs - 4u);
    assert_int_equal(km_servo_id(&fx.s), ID);
    assert_int_equal(reg_by_addr(0x10), 10000);
    assert_int_equal(reg_by_addr(0x16), 99);
    assert_int_equal(reg_by_addr(0x17), 55);
    assert_int_equal(reg_by_addr(0x5B), 1000);
    assert_int_equal(reg_by_addr(0x5C), kt_product_pot()->max_current_ma);
    assert_int_equal(reg_by_addr(0x5D), kt_product_pot()->max_speed_dps);
    assert_int_equal(km_servo_status(&fx.s), 0);
}

/* "User-data reset" level 2: everything, ID, baud and 0x17 included, except
 * the factory data: 0x16 keeps this unit's stored calibration (99 here, not
 * the product's 37) and is not in the commit. */
static void test_s5_1_0x03_userdata_reset_level2(void **state)
{
    (void)state;
    init_changed();
    assert_int_equal(reg_by_addr(0x16), 99);
    kt_write_u8(&fx, ID, 0x03, 2);
    kt_no_reply(&fx); /* 0x11 back to level 0 */
    assert_int_equal(fx.fake.n_commits, 1);
    const kt_commit_t *c = &fx.fake.commits[0];
    assert_true(c->accepted);
    assert_int_equal(c->n, sizeof persisted_addrs - 1u);
    for (unsigned i = 0; i < sizeof persisted_addrs; i++) {
        const uint8_t a = persisted_addrs[i];
        if (a == 0x16) {
            assert_false(kt_commit_has(c, a));
            continue;
        }
        assert_int_equal(kt_commit_value(c, a), spec_default(a, kt_product_pot()));
        assert_int_equal(reg_by_addr(a), spec_default(a, kt_product_pot()));
    }
    assert_int_equal(km_servo_id(&fx.s), 0);
    assert_int_equal(reg_by_addr(0x16), 99);
    assert_int_equal(reg_by_addr(0x5B), 1000);
    assert_int_equal(km_servo_active_baud(&fx.s), 1000000); /* baud applies at restart */
    assert_int_equal(km_servo_status(&fx.s), 0);
}

/* A reset whose commit fails changes nothing, bit 6. The servo of
 * init_changed() is at response level 1 (0x11 = 0x0B) and stays there, so
 * the write answers its own bit 6 and leaves nothing for the next ping. */
static void test_s5_1_0x03_userdata_reset_commit_fails(void **state)
{
    (void)state;
    init_changed();
    fx.fake.fail_next_commit = true;
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_write_u8(&fx, ID, 0x03, 2);
    kt_reply_is_status(&fx, ID, KM_ST_FAILED);
    sn.n_commits++; /* the refused attempt */
    kt_assert_unchanged(&fx, &sn);
    assert_false(fx.fake.commits[0].accepted);
    kt_ping_is(&fx, ID, 0);
    /* the same at response level 0: the bit waits for the next ping */
    kt_write_u8(&fx, ID, 0x11, 0x03);
    kt_no_reply(&fx);
    fx.fake.fail_next_commit = true;
    kt_snap(&fx, &sn);
    kt_write_u8(&fx, ID, 0x03, 1);
    kt_no_reply(&fx);
    sn.n_commits++;
    sn.unreported |= KM_ST_FAILED;
    kt_assert_unchanged(&fx, &sn);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    kt_ping_is(&fx, ID, 0);
}

/* Commit failure of a plain persisted write: bit 6, the old value (and its
 * mirror) stays. */
static void test_s5_commit_failure_keeps_old_value(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    answering();
    fx.fake.fail_next_commit = true;
    kt_write_u16(&fx, ID, 0x13, 400);
    kt_reply_is_status(&fx, ID, KM_ST_FAILED);
    kt_read(&fx, ID, 0x13);
    assert_int_equal(kt_read_le(&fx, 0x13), 1000);
    kt_read(&fx, ID, 0x5B);
    assert_int_equal(kt_read_le(&fx, 0x5B), 1000);
}

/* §5.4 0x5B/0x5C/0x5D follow 0x13/0x14/0x15; writing a mirror leaves the
 * stored register alone and commits nothing. */
static void test_s5_4_mirrors_follow(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    static const uint8_t src[] = {0x13, 0x14, 0x15}, dst[] = {0x5B, 0x5C, 0x5D};
    for (unsigned i = 0; i < 3; i++) {
        kt_write_u16(&fx, ID, src[i], 321);
        kt_read(&fx, ID, dst[i]);
        assert_int_equal(kt_read_le(&fx, dst[i]), 321);
        const unsigned c0 = fx.fake.n_commits;
        kt_write_u16(&fx, ID, dst[i], 123);
        assert_int_equal(fx.fake.n_commits, c0);
        kt_read(&fx, ID, dst[i]);
        assert_int_equal(kt_read_le(&fx, dst[i]), 123);
        kt_read(&fx, ID, src[i]);
        assert_int_equal(kt_read_le(&fx, src[i]), 321);
    }
}

/* §5.4 0x64: each write is a request; 5 not writable; 3 turns to 2 at a
 * rotation command; rotation refused with 0 or 1 (and 5). */
static void test_s5_4_0x64_torque_switch(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    assert_int_equal(reg_by_addr(0x64), 3);
    move_time(ID);
    assert_int_equal(fx.fake.n_requests, 1);
    assert_int_equal(reg_by_addr(0x64), 2);
    for (uint8_t v = 0; v <= 1; v++) {
        kt_write_u8(&fx, ID, 0x64, v);
        const unsigned n = fx.fake.n_requests;
        assert_int_equal(fx.fake.requests[n - 1].kind, KM_REQ_TORQUE);
        assert_int_equal(fx.fake.requests[n - 1].u.torque, v);
        kt_ping_is(&fx, ID, 0); /* the write of v was good */
        move_time(ID);
        assert_int_equal(fx.fake.n_requests, n);
        kt_ping_is(&fx, ID, KM_ST_FAILED); /* the refused move */
        assert_int_equal(reg_by_addr(0x64), v);
    }
    kt_write_u8(&fx, ID, 0x64, 5);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    assert_int_equal(reg_by_addr(0x64), 1);
    km_live_t prot = {0}; /* control, after a protection: 0x64 = 5, set by the servo */
    prot.protecting = true;
    prot.torque_forced = true;
    prot.torque_switch = KM_TORQUE_PROTECTED;
    km_servo_set_live(&fx.s, &prot);
    kt_read(&fx, ID, 0x64);
    assert_int_equal(kt_read_le(&fx, 0x64), 5);
    const unsigned n = fx.fake.n_requests;
    move_time(ID);
    assert_int_equal(fx.fake.n_requests, n);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    kt_write_u8(&fx, ID, 0x64, 2);
    move_time(ID);
    kt_ping_is(&fx, ID, 0);
    assert_int_equal(fx.fake.n_requests, n + 2);
    assert_int_equal(fx.fake.requests[n + 1].kind, KM_REQ_MOVE);
    assert_int_equal(fx.fake.requests[n + 1].u.move.kind, KM_MOVE_TIME);
    assert_int_equal(reg_by_addr(0x64), 2);
}

/* §5.4 0x5A: 1 servo only refuses motor commands, 2 motor only refuses servo
 * commands; switching to 2 is refused while running with torque on. Each
 * outcome is read with a ping (level 0: nothing else reports it). */
static void test_s5_4_0x5A_control_mode(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_write_u8(&fx, ID, 0x5A, 1);
    kt_ping_is(&fx, ID, 0);
    motor_torque(ID, 300);
    assert_int_equal(fx.fake.n_requests, 0);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    move_time(ID);
    assert_int_equal(fx.fake.n_requests, 1);
    kt_ping_is(&fx, ID, 0);
    kt_write_u8(&fx, ID, 0x5A, 2); /* idle: allowed */
    assert_int_equal(reg_by_addr(0x5A), 2);
    kt_ping_is(&fx, ID, 0);
    move_time(ID);
    assert_int_equal(fx.fake.n_requests, 1);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    motor_torque(ID, -300);
    assert_int_equal(fx.fake.n_requests, 2);
    assert_int_equal(fx.fake.requests[1].kind, KM_REQ_MOTOR);
    assert_int_equal(fx.fake.requests[1].u.run.mode, KM_RUN_PWM);
    assert_true(fx.fake.requests[1].u.run.reverse);
    assert_int_equal(fx.fake.requests[1].u.run.value, 300);
    assert_int_equal(fx.fake.requests[1].u.run.until, KM_UNTIL_NONE);
    assert_int_equal(fx.fake.requests[1].u.run.after, KM_AFTER_IDLE);
    kt_ping_is(&fx, ID, 0);
    kt_write_u8(&fx, ID, 0x5A, 0);
    km_live_t live = {0};
    live.running = true;
    km_servo_set_live(&fx.s, &live);
    kt_write_u8(&fx, ID, 0x64, 2);
    kt_ping_is(&fx, ID, KM_ST_RUNNING);
    kt_write_u8(&fx, ID, 0x5A, 2); /* running with torque on: refused */
    kt_ping_is(&fx, ID, KM_ST_RUNNING | KM_ST_FAILED);
    assert_int_equal(reg_by_addr(0x5A), 0);
    kt_write_u8(&fx, ID, 0x64, 0);
    kt_write_u8(&fx, ID, 0x5A, 2); /* torque off: allowed */
    kt_ping_is(&fx, ID, KM_ST_RUNNING);
    assert_int_equal(reg_by_addr(0x5A), 2);
}

/* §5.1 0x18 adds to 0x17 (committed) within ±zero_offset2_max. */
static void test_s5_1_0x18_increments_0x17(void **state)
{
    (void)state;
    const int16_t max = kt_product_pot()->zero_offset2_max;
    kt_init(&fx, kt_product_pot(), ID);
    kt_write_u8(&fx, ID, 0x18, 50);
    assert_int_equal((int16_t)reg_by_addr(0x17), 50);
    assert_int_equal(kt_commit_value(&fx.fake.commits[0], 0x17), 50);
    kt_write_u8(&fx, ID, 0x18, (uint8_t)-100);
    assert_int_equal((int16_t)reg_by_addr(0x17), -50);
    kt_write_u16(&fx, ID, 0x17, (uint16_t)(max - 10));
    kt_write_u8(&fx, ID, 0x18, 10); /* exactly max */
    assert_int_equal((int16_t)reg_by_addr(0x17), max);
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_write_u8(&fx, ID, 0x18, 1); /* max + 1 */
    sn.unreported |= KM_ST_FAILED; /* level 0: the next ping reports it */
    kt_assert_unchanged(&fx, &sn);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    kt_write_u16(&fx, ID, 0x17, (uint16_t)(int16_t)-max);
    kt_snap(&fx, &sn);
    kt_write_u8(&fx, ID, 0x18, (uint8_t)-1);
    sn.unreported |= KM_ST_FAILED;
    kt_assert_unchanged(&fx, &sn);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    kt_write_u8(&fx, ID, 0x18, 0); /* pot: adds 0, no zeroing request */
    assert_int_equal((int16_t)reg_by_addr(0x17), -max);
    for (unsigned i = 0; i < fx.fake.n_requests; i++) {
        assert_int_not_equal(fx.fake.requests[i].kind, KM_REQ_ZERO_POSITION);
    }
}

/* §5.1 0x18 = 0 on an encoder: zero the current position, 0x17 unchanged. */
static void test_s5_1_0x18_zero_on_encoder(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_enc(), ID);
    kt_write_u8(&fx, ID, 0x18, 0);
    assert_int_equal(fx.fake.n_requests, 1);
    assert_int_equal(fx.fake.requests[0].kind, KM_REQ_ZERO_POSITION);
    assert_int_equal(reg_by_addr(0x17), 0);
    assert_int_equal(fx.fake.n_commits, 0);
}

/* §5.2 0x36: write 1 to a bit to clear that protection: a request, nothing
 * stored. "Reserved bits": bits 4..7 are accepted and dropped, so 0x10 is a
 * request to clear nothing and 0xF9 clears 0x09. */
static void test_s5_2_0x36_write_one_to_clear(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_write_u8(&fx, ID, 0x36, 0x09);
    assert_int_equal(fx.fake.n_requests, 1);
    assert_int_equal(fx.fake.requests[0].kind, KM_REQ_PROTECTION_CLEAR);
    assert_int_equal(fx.fake.requests[0].u.clear, 0x09);
    assert_int_equal(fx.fake.n_commits, 0);
    kt_write_u8(&fx, ID, 0x36, 0x10);
    assert_int_equal(fx.fake.n_requests, 2);
    assert_int_equal(fx.fake.requests[1].kind, KM_REQ_PROTECTION_CLEAR);
    assert_int_equal(fx.fake.requests[1].u.clear, 0x00);
    kt_write_u8(&fx, ID, 0x36, 0xF9);
    assert_int_equal(fx.fake.n_requests, 3);
    assert_int_equal(fx.fake.requests[2].u.clear, 0x09);
    assert_int_equal(fx.fake.n_commits, 0);
    kt_ping_is(&fx, ID, 0);
    kt_read(&fx, ID, 0x36);
    const uint8_t none = 0;
    kt_reply_is_read(&fx, ID, 0x36, &none, 1); /* the live protections, not the write */
}

static void read_pos(uint8_t addr, int32_t v)
{
    km_live_t live = {0};
    if (addr == 0x46)
        live.position = v;
    else
        live.deviation = v;
    km_servo_set_live(&fx.s, &live);
    kt_read(&fx, ID, addr);
    uint8_t want[4];
    const unsigned n = (v >= -32768 && v <= 32767) ? 2u : 4u;
    for (unsigned i = 0; i < n; i++)
        want[i] = (uint8_t)((uint32_t)v >> (8u * i));
    kt_reply_is_read(&fx, ID, addr, want, n);
}

/* §5.3 0x46/0x4C: i16 when the value fits, else i32. */
static void test_s5_3_0x46_0x4C_i16_or_i32(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_enc(), ID);
    static const int32_t vals[] = {0, 900, -900, 32767, -32768, 32768, -32769, 123456, -7000000};
    static const uint8_t addrs[] = {0x46, 0x4C};
    for (unsigned a = 0; a < 2; a++) {
        for (unsigned i = 0; i < sizeof vals / sizeof vals[0]; i++) {
            read_pos(addrs[a], vals[i]);
        }
    }
    assert_int_equal(fx.reply.len, 11);
}

/* §5.3 the other live registers: i16 (speed, current, PWM, temperature,
 * voltage) and u32 rotation time. */
static void test_s5_3_live_reads(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    km_live_t live = {0};
    live.speed = -120;
    live.current = 1500;
    live.pwm = 999;
    live.temperature = 41;
    live.voltage = 12100;
    live.rotation_ms = 0x01020304u;
    km_servo_set_live(&fx.s, &live);
    static const struct {
        uint8_t addr;
        int16_t v;
    } i16s[] = {{0x47, -120}, {0x48, 1500}, {0x49, 999}, {0x4A, 41}, {0x4B, 12100}};
    for (unsigned i = 0; i < 5; i++) {
        kt_read(&fx, ID, i16s[i].addr);
        const uint8_t want[2] = {(uint8_t)i16s[i].v, (uint8_t)((uint16_t)i16s[i].v >> 8)};
        kt_reply_is_read(&fx, ID, i16s[i].addr, want, 2);
    }
    kt_read(&fx, ID, 0x4D);
    const uint8_t t[] = {0x04, 0x03, 0x02, 0x01};
    kt_reply_is_read(&fx, ID, 0x4D, t, 4);
}

/* §6: encoder-only commands on a potentiometer product: bit 6, no request. */
static void test_s6_encoder_only_commands_refused_on_pot(void **state)
{
    (void)state;
    static const struct {
        uint8_t addr, n, v[5];
    } cmds[] = {
        {0x6F, 2, {0x64, 0x00}},                   /* motor constant speed */
        {0x70, 5, {0x20, 0x5A, 0x00, 0x64, 0x00}}, /* p1 = angle */
        {0x70, 5, {0x30, 0x0A, 0x00, 0x64, 0x00}}, /* p1 = turns */
        {0x70, 5, {0x04, 0x00, 0x00, 0x64, 0x00}}, /* p2 = speed */
        {0x46, 2, {0x00, 0x00}},                   /* zeroing */
        {0x46, 4, {0x00, 0x00, 0x00, 0x00}},
    };
    for (unsigned i = 0; i < sizeof cmds / sizeof cmds[0]; i++) {
        kt_init(&fx, kt_product_pot(), ID);
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        kt_write(&fx, ID, cmds[i].addr, cmds[i].v, cmds[i].n);
        sn.unreported |= KM_ST_FAILED; /* level 0: the next ping reports it */
        kt_assert_unchanged(&fx, &sn);
        assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
        /* the same on an encoder product is accepted */
        kt_init(&fx, kt_product_enc(), ID);
        kt_write(&fx, ID, cmds[i].addr, cmds[i].v, cmds[i].n);
        assert_int_equal(km_servo_status(&fx.s), 0);
        assert_int_equal(fx.fake.n_requests, 1);
    }
    /* 0x70 with time and PWM works on a pot */
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t ok[] = {0x10, 0x14, 0x00, 0xF4, 0x01};
    kt_write(&fx, ID, 0x70, ok, 5);
    assert_int_equal(fx.fake.n_requests, 1);
    assert_int_equal(fx.fake.requests[0].kind, KM_REQ_MOTOR);
    assert_int_equal(fx.fake.requests[0].u.run.mode, KM_RUN_PWM); /* p2 kind 0 */
    assert_false(fx.fake.requests[0].u.run.reverse);              /* bit 0 */
    assert_int_equal(fx.fake.requests[0].u.run.value, 500);
    assert_int_equal(fx.fake.requests[0].u.run.until, KM_UNTIL_TIME); /* p1 kind 1 */
    assert_int_equal(fx.fake.requests[0].u.run.amount, 20);
    assert_int_equal(fx.fake.requests[0].u.run.after, KM_AFTER_FREE); /* bit 1 */
}

/* §5.3 0x46 write on an encoder: any value zeroes the position. */
static void test_s5_3_0x46_zeroing_on_encoder(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_enc(), ID);
    const uint8_t v2[] = {0x34, 0x12}, v4[] = {0x01, 0x02, 0x03, 0x04};
    kt_write(&fx, ID, 0x46, v2, 2);
    kt_write(&fx, ID, 0x46, v4, 4);
    assert_int_equal(fx.fake.n_requests, 2);
    assert_int_equal(fx.fake.requests[0].kind, KM_REQ_ZERO_POSITION);
    assert_int_equal(fx.fake.requests[1].kind, KM_REQ_ZERO_POSITION);
    assert_int_equal(fx.fake.n_commits, 0);
}

/* §5.4 servo-mode commands: their typed requests carry the values sent. */
static void test_s5_4_servo_commands_requests(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t sp[] = {0x7C, 0xFC, 0x2C, 0x01}; /* -900, 300 deg/s */
    kt_write(&fx, ID, 0x66, sp, 4);
    const uint8_t ip[] = {0x0A, 0x00};
    kt_write(&fx, ID, 0x68, ip, 2);
    const uint8_t adv[] = {0x12, 0x64, 0x00, 0xF4, 0x01}; /* relative, max PWM 500 */
    kt_write(&fx, ID, 0x67, adv, 5);
    assert_int_equal(fx.fake.n_requests, 3);
    assert_int_equal(fx.fake.requests[0].kind, KM_REQ_MOVE);
    assert_int_equal(fx.fake.requests[0].u.move.kind, KM_MOVE_SPEED);
    assert_false(fx.fake.requests[0].u.move.relative);
    assert_int_equal(fx.fake.requests[0].u.move.target, -900);
    assert_int_equal(fx.fake.requests[0].u.move.time_or_speed, 300);
    assert_int_equal(fx.fake.requests[0].u.move.pwm_cap, 1000);
    assert_int_equal(fx.fake.requests[1].kind, KM_REQ_MOVE);
    assert_int_equal(fx.fake.requests[1].u.move.kind, KM_MOVE_STREAM);
    assert_int_equal(fx.fake.requests[1].u.move.target, 10);
    /* 0x67 0x12: high nibble 1 relative, low nibble 2 a PWM cap at the fastest speed */
    assert_int_equal(fx.fake.requests[2].kind, KM_REQ_MOVE);
    assert_int_equal(fx.fake.requests[2].u.move.kind, KM_MOVE_SPEED);
    assert_true(fx.fake.requests[2].u.move.relative);
    assert_int_equal(fx.fake.requests[2].u.move.target, 100);
    assert_int_equal(fx.fake.requests[2].u.move.time_or_speed, 0);
    assert_int_equal(fx.fake.requests[2].u.move.pwm_cap, 500);
    const uint8_t bad[] = {0x12, 0x64, 0x00, 0xE9, 0x03}; /* max PWM 1001 */
    kt_write(&fx, ID, 0x67, bad, 5);
    assert_int_equal(fx.fake.n_requests, 3);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
}

/* ---- "Extension command 0x7F" ------------------------------------------ */

/* Each extension address, own ID, as whole frames:
 * F9 FF id 03 7F addr cs -> F9 F5 id len 7F addr value cs. */
static void test_ext_0x7F_each_address(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    /* 0x01 user-data source: loaded from flash (0) */
    kt_send_hex(&fx, "F9 FF 01 03 7F 01 7B");
    kt_reply_is_hex(&fx, "F9 F5 01 04 7F 01 00 7A");
    assert_int_equal(fx.reply.delay_us, 200);
    km_servo_set_userdata_source(&fx.s, KM_USERDATA_DEFAULTS_INVALID);
    kt_send_hex(&fx, "F9 FF 01 03 7F 01 7B");
    kt_reply_is_hex(&fx, "F9 F5 01 04 7F 01 03 77");
    /* 0x02 reset cause: power-on (0), then software (2) */
    kt_send_hex(&fx, "F9 FF 01 03 7F 02 7A");
    kt_reply_is_hex(&fx, "F9 F5 01 04 7F 02 00 79");
    km_servo_set_reset_cause(&fx.s, 2);
    kt_send_hex(&fx, "F9 FF 01 03 7F 02 7A");
    kt_reply_is_hex(&fx, "F9 F5 01 04 7F 02 02 77");
    /* 0x03 active baud / 100, u16: 1152 = 80 04 */
    kt_send_hex(&fx, "F9 FF 01 03 7F 03 79");
    kt_reply_is_hex(&fx, "F9 F5 01 05 7F 03 80 04 F3");
    kt_write_u16(&fx, 1, 0x10, 5000); /* stored; in force only after restart */
    kt_send_hex(&fx, "F9 FF 01 03 7F 03 79");
    kt_reply_is_hex(&fx, "F9 F5 01 05 7F 03 80 04 F3");
    km_servo_set_active_baud(&fx.s, 9600); /* the board fell back */
    kt_send_hex(&fx, "F9 FF 01 03 7F 03 79");
    kt_reply_is_hex(&fx, "F9 F5 01 05 7F 03 60 00 17");
    kt_ping_is(&fx, 1, 0);
}

/* An address 0x7F does not have, or a missing or extra address byte: bit 5
 * and the short response with the command's own status, nothing changes. */
static void test_ext_0x7F_bad_address_or_length(void **state)
{
    (void)state;
    static const char *frames[] = {
        "F9 FF 01 03 7F 00 7C",    /* address 0 */
        "F9 FF 01 03 7F 09 73",    /* address 9 */
        "F9 FF 01 03 7F 04 78",    /* the first address after the last one */
        "F9 FF 01 03 7F FF 7D",    /* address 0xFF */
        "F9 FF 01 02 7F 7D",       /* no address byte */
        "F9 FF 01 04 7F 01 00 7A", /* an extra byte after a good address */
    };
    for (unsigned i = 0; i < sizeof frames / sizeof frames[0]; i++) {
        kt_init(&fx, kt_product_pot(), 1);
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        kt_send_hex(&fx, frames[i]);
        kt_reply_is_hex(&fx, "F9 F5 01 02 20 DC");
        assert_int_equal(fx.reply.delay_us, 200);
        kt_assert_unchanged(&fx, &sn); /* its own answer carried the bit 5 */
        kt_ping_is(&fx, 1, 0);
    }
}

/* "Super ID": 0x7F is a query like 0x02: every servo answers with its own
 * ID in its slot, slot = the longest extension answer, 7 + 2 bytes, at the
 * active baud; an error answer is a short response (6 bytes). */
static void test_ext_0x7F_super_id_slots(void **state)
{
    (void)state;
    static const uint8_t ids[] = {0, 1, 3, 250};
    assert_int_equal(kt_slot_us(9, 115200), 955); /* 110 bits: 954.9 us */
    for (unsigned i = 0; i < sizeof ids; i++) {
        kt_init(&fx, kt_product_pot(), ids[i]);
        uint8_t want[16];
        static const uint8_t src[] = {0x01, 0x00};
        kt_ext_read(&fx, KM_ID_SUPER, 0x01);
        const unsigned n = kt_response(want, ids[i], 0x7F, src, 2);
        assert_int_equal(fx.reply.len, n);
        assert_memory_equal(fx.reply.bytes, want, n);
        assert_int_equal(fx.reply.delay_us, 200u + ids[i] * kt_slot_us(9, 115200));
        kt_ext_read(&fx, KM_ID_SUPER, 0x03); /* the longest answer: same slot */
        static const uint8_t baud[] = {0x03, 0x80, 0x04};
        const unsigned n3 = kt_response(want, ids[i], 0x7F, baud, 3);
        assert_int_equal(fx.reply.len, n3);
        assert_memory_equal(fx.reply.bytes, want, n3);
        assert_int_equal(fx.reply.delay_us, 200u + ids[i] * kt_slot_us(9, 115200));
        kt_ext_read(&fx, KM_ID_SUPER, 0x09);
        kt_reply_is_status(&fx, ids[i], KM_ST_EXCEPTION);
        assert_int_equal(fx.reply.delay_us, 200u + ids[i] * kt_slot_us(6, 115200));
        /* at 9600 baud from the store, and at a board's fallback baud */
        kt_persisted_set(&fx, 0x10, 96);
        kt_reinit(&fx, kt_product_pot());
        kt_ext_read(&fx, KM_ID_SUPER, 0x01);
        assert_int_equal(fx.reply.delay_us, 200u + ids[i] * kt_slot_us(9, 9600));
        km_servo_set_active_baud(&fx.s, 57600);
        kt_ext_read(&fx, KM_ID_SUPER, 0x02);
        assert_int_equal(fx.reply.delay_us, 200u + ids[i] * kt_slot_us(9, 57600));
    }
}

/* Broadcast 0x7F: executed, never answered, nothing changes. */
static void test_ext_0x7F_broadcast_no_answer(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_send_hex(&fx, "F9 FF FE 03 7F 01 7E");
    kt_no_reply(&fx);
    kt_assert_unchanged(&fx, &sn);
    kt_ping_is(&fx, 1, 0);
}

/* "One life cycle for bits 5 and 6" rule 4: an extension read reports its
 * own outcome only; unreported bits (a checksum error, a failed level-0
 * write) stay for the next ping. */
static void test_ext_0x7F_keeps_unreported_bits(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    km_servo_note_checksum_error(&fx.s);
    kt_send_hex(&fx, "F9 FF 01 05 03 13 E9 03 F7"); /* 1001: fails, level 0 */
    kt_no_reply(&fx);
    kt_send_hex(&fx, "F9 FF 01 03 7F 01 7B");
    kt_reply_is_hex(&fx, "F9 F5 01 04 7F 01 00 7A");
    kt_send_hex(&fx, "F9 FF 01 03 7F 09 73");
    kt_reply_is_hex(&fx, "F9 F5 01 02 20 DC"); /* own bit 5 only, not 0x60 */
    kt_send_hex(&fx, "F9 FF FD 03 7F 01 7F");
    kt_reply_is_hex(&fx, "F9 F5 01 04 7F 01 00 7A");
    assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION | KM_ST_FAILED);
    kt_send_hex(&fx, "F9 FF 01 02 01 FB");
    kt_reply_is_hex(&fx, "F9 F5 01 02 60 9C");
    kt_send_hex(&fx, "F9 FF 01 02 01 FB");
    kt_reply_is_hex(&fx, "F9 F5 01 02 00 FC");
}

/* ---- init without a store ------------------------------------------------ */

/* km_servo_init(persisted = NULL): every register at its §5 / product
 * default, 0x5B..0x5D equal to 0x13..0x15 (§5.4), the active baud the
 * default 115200, ID 0. */
static void test_s5_init_without_store_all_defaults(void **state)
{
    (void)state;
    const km_product_t *ps[2] = {kt_product_pot(), kt_product_enc()};
    for (unsigned pi = 0; pi < 2; pi++) {
        const km_product_t *p = ps[pi];
        kt_init(&fx, p, 5);
        memset(&fx.s, 0xA5, sizeof fx.s); /* nothing may survive from before */
        km_servo_init(&fx.s, p, NULL, 1, &fx.ops);
        for (unsigned i = 0; i < sizeof persisted_addrs; i++) {
            const uint8_t a = persisted_addrs[i];
            if (reg_by_addr(a) != spec_default(a, p)) {
                fail_msg("0x%02X = 0x%X, want 0x%X", a, (unsigned)reg_by_addr(a),
                         (unsigned)spec_default(a, p));
            }
        }
        assert_int_equal(reg_by_addr(0x5B), 1000);
        assert_int_equal(reg_by_addr(0x5C), p->max_current_ma);
        assert_int_equal(reg_by_addr(0x5D), p->max_speed_dps);
        assert_int_equal(reg_by_addr(0x5B), reg_by_addr(0x13));
        assert_int_equal(reg_by_addr(0x5C), reg_by_addr(0x14));
        assert_int_equal(reg_by_addr(0x5D), reg_by_addr(0x15));
        assert_int_equal(reg_by_addr(0x5A), 0);
        assert_int_equal(reg_by_addr(0x64), 3);
        assert_int_equal(km_servo_active_baud(&fx.s), 115200);
        assert_int_equal(km_servo_id(&fx.s), 0);
        assert_int_equal(km_servo_status(&fx.s), 0);
        assert_false(fx.s.sync.full);
        kt_ping_is(&fx, 0, 0);
        kt_ext_read(&fx, 0, 0x03);
        uint8_t want[16];
        static const uint8_t baud[] = {0x03, 0x80, 0x04};
        const unsigned n = kt_response(want, 0, 0x7F, baud, 3);
        assert_int_equal(fx.reply.len, n);
        assert_memory_equal(fx.reply.bytes, want, n);
        assert_int_equal(fx.fake.n_commits, 0);
    }
}

/* ---- "Limits that contradict each other" --------------------------------- */

/* 0x5B <= 0x13, 0x5C <= 0x14, 0x5D <= 0x15: at the maximum accepted, one
 * above refused with bit 6 and nothing changes; a write of the maximum
 * register moves the runtime limit with it, down and up (§5.4 "follows"). */
static void test_limits_runtime_not_above_maximum(void **state)
{
    (void)state;
    static const struct {
        uint8_t max_addr, lim_addr;
        uint16_t m;
    } c[] = {
        {0x13, 0x5B, 500},
        {0x14, 0x5C, 1500},
        {0x15, 0x5D, 500},
    };
    for (unsigned i = 0; i < 3; i++) {
        kt_init(&fx, kt_product_pot(), ID);
        kt_write_u16(&fx, ID, c[i].max_addr, c[i].m);
        assert_int_equal(reg_by_addr(c[i].lim_addr), c[i].m);
        kt_write_u16(&fx, ID, c[i].lim_addr, (uint16_t)(c[i].m - 1));
        kt_ping_is(&fx, ID, 0);
        kt_write_u16(&fx, ID, c[i].lim_addr, c[i].m); /* at the edge */
        kt_ping_is(&fx, ID, 0);
        assert_int_equal(reg_by_addr(c[i].lim_addr), c[i].m);
        kt_write_u16(&fx, ID, c[i].lim_addr, (uint16_t)(c[i].m - 1));
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        kt_write_u16(&fx, ID, c[i].lim_addr, (uint16_t)(c[i].m + 1)); /* past it */
        sn.unreported |= KM_ST_FAILED;
        kt_assert_unchanged(&fx, &sn);
        kt_ping_is(&fx, ID, KM_ST_FAILED);
        kt_write_u16(&fx, ID, c[i].lim_addr, 0);
        kt_ping_is(&fx, ID, 0);
        assert_int_equal(reg_by_addr(c[i].lim_addr), 0);
        kt_write_u16(&fx, ID, c[i].max_addr, (uint16_t)(c[i].m + 100)); /* follows up */
        assert_int_equal(reg_by_addr(c[i].lim_addr), c[i].m + 100);
        kt_write_u16(&fx, ID, c[i].max_addr, 200); /* and down */
        assert_int_equal(reg_by_addr(c[i].lim_addr), 200);
        kt_ping_is(&fx, ID, 0);
    }
}

static void write_i16(uint8_t addr, int16_t v)
{
    kt_write_u16(&fx, ID, addr, (uint16_t)v);
}

static void angles_are(int16_t lo, int16_t hi)
{
    assert_int_equal((int16_t)reg_by_addr(0x19), lo);
    assert_int_equal((int16_t)reg_by_addr(0x1A), hi);
}

/* A write that must be refused: bit 6 at the next ping, nothing changes,
 * nothing committed. */
static void refused_i16(uint8_t addr, int16_t v)
{
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    write_i16(addr, v);
    sn.unreported |= KM_ST_FAILED;
    kt_assert_unchanged(&fx, &sn);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
}

static void accepted_i16(uint8_t addr, int16_t v)
{
    const unsigned c0 = fx.fake.n_commits;
    write_i16(addr, v);
    kt_ping_is(&fx, ID, 0);
    assert_int_equal(fx.fake.n_commits, c0 + 1u);
    assert_int_equal((int16_t)reg_by_addr(addr), v);
}

/* 0x19 < 0x1A when both are set: at the edge (min = max) and past it
 * refused; one below accepted; 0 = no limit on either side is always
 * consistent. */
static void test_limits_angle_min_below_max(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID); /* -1350 .. 1350 */
    accepted_i16(0x19, 1349);
    refused_i16(0x19, 1350); /* min = max */
    angles_are(1349, 1350);
    kt_init(&fx, kt_product_pot(), ID);
    accepted_i16(0x1A, -1349);
    refused_i16(0x1A, -1350); /* max = min */
    angles_are(-1350, -1349);
    kt_init(&fx, kt_product_pot(), ID);
    accepted_i16(0x1A, 500);
    refused_i16(0x19, 1000); /* min > max */
    angles_are(-1350, 500);
    /* 0 = no limit */
    accepted_i16(0x1A, 0);
    accepted_i16(0x19, 1350); /* no maximum: any minimum */
    refused_i16(0x1A, 1350);  /* both set again: min = max */
    refused_i16(0x1A, 100);
    accepted_i16(0x19, 0);
    accepted_i16(0x1A, -1350); /* no minimum: any maximum */
    refused_i16(0x19, -1350);
    accepted_i16(0x1A, 0);
    angles_are(0, 0);
}

/* Moving the window past itself: the order that keeps min < max works, the
 * other is refused at its first write (nothing changes). */
static void test_limits_angle_window_both_write_orders(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    accepted_i16(0x19, -1000);
    accepted_i16(0x1A, -500);
    /* to 500 .. 1000: minimum first is refused (500 >= -500) */
    refused_i16(0x19, 500);
    angles_are(-1000, -500);
    accepted_i16(0x1A, 1000); /* maximum first */
    accepted_i16(0x19, 500);
    angles_are(500, 1000);
    /* back to -1000 .. -500: maximum first is refused (-500 <= 500) */
    refused_i16(0x1A, -500);
    angles_are(500, 1000);
    accepted_i16(0x19, -1000); /* minimum first */
    accepted_i16(0x1A, -500);
    angles_are(-1000, -500);
}

/* Stored angle limits that contradict each other (a damaged store) both
 * start at the product defaults; consistent ones, 0 = no limit included,
 * are kept; nothing else is touched. */
static void test_limits_angle_stored_contradicting_at_init(void **state)
{
    (void)state;
    static const struct {
        int16_t lo, hi;
        bool kept;
    } c[] = {
        {1000, 500, false}, {500, 500, false}, {-1, -2, false},     {0, -500, true},
        {-500, 0, true},    {0, 0, true},      {-1000, 1000, true}, {1349, 1350, true},
    };
    const km_product_t *p = kt_product_pot();
    for (unsigned i = 0; i < sizeof c / sizeof c[0]; i++) {
        kt_init(&fx, p, ID);
        kt_persisted_set(&fx, 0x19, (uint16_t)c[i].lo);
        kt_persisted_set(&fx, 0x1A, (uint16_t)c[i].hi);
        kt_persisted_set(&fx, 0x13, 700);
        kt_reinit(&fx, p);
        if (c[i].kept) {
            angles_are(c[i].lo, c[i].hi);
        } else {
            angles_are(p->angle_min, p->angle_max);
        }
        assert_int_equal(reg_by_addr(0x13), 700);
        assert_int_equal(km_servo_id(&fx.s), ID);
        assert_int_equal(km_servo_status(&fx.s), 0);
    }
    /* the encoder product's defaults are 0, 0 (no limits) */
    kt_init(&fx, kt_product_enc(), ID);
    kt_persisted_set(&fx, 0x19, 100);
    kt_persisted_set(&fx, 0x1A, (uint16_t)-100);
    kt_reinit(&fx, kt_product_enc());
    angles_are(0, 0);
}

/* ---- "Zeroing" ------------------------------------------------------------ */

/* With a hardware fault latched, both zeroing paths (a write of 0x46, 0x18
 * = 0 on an encoder) are refused with bit 6 and send no request; an
 * ordinary 0x18 increment still works; after the restart (re-init) that
 * clears the fault, zeroing works again. */
static void test_zeroing_refused_while_fault_latched(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_enc(), ID);
    km_live_t live = {0};
    live.hw_faults = 0x20; /* position sensor */
    km_servo_set_live(&fx.s, &live);
    live.hw_faults = 0;
    km_servo_set_live(&fx.s, &live); /* gone from the sensors, still latched */
    static const uint8_t v2[] = {0x00, 0x00}, v4[] = {0x01, 0x02, 0x03, 0x04};
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_write(&fx, ID, 0x46, v2, 2);
    sn.unreported |= KM_ST_FAILED;
    kt_assert_unchanged(&fx, &sn);
    kt_ping_is(&fx, ID, KM_ST_HW_FAULT | KM_ST_FAILED);
    kt_snap(&fx, &sn);
    kt_write(&fx, ID, 0x46, v4, 4);
    sn.unreported |= KM_ST_FAILED;
    kt_assert_unchanged(&fx, &sn);
    kt_ping_is(&fx, ID, KM_ST_HW_FAULT | KM_ST_FAILED);
    kt_snap(&fx, &sn);
    kt_write_u8(&fx, ID, 0x18, 0);
    sn.unreported |= KM_ST_FAILED;
    kt_assert_unchanged(&fx, &sn); /* 0x17 unchanged, nothing committed */
    kt_ping_is(&fx, ID, KM_ST_HW_FAULT | KM_ST_FAILED);
    /* at response level 1 the write's own answer says so */
    kt_write_u8(&fx, ID, 0x11, 0x0A);
    kt_reply_is_status(&fx, ID, KM_ST_HW_FAULT);
    kt_write(&fx, ID, 0x46, v2, 2);
    kt_reply_is_status(&fx, ID, KM_ST_HW_FAULT | KM_ST_FAILED);
    kt_write_u8(&fx, ID, 0x18, 0);
    kt_reply_is_status(&fx, ID, KM_ST_HW_FAULT | KM_ST_FAILED);
    /* an ordinary increment only changes 0x17 */
    const unsigned c0 = fx.fake.n_commits;
    kt_write_u8(&fx, ID, 0x18, 5);
    kt_reply_is_status(&fx, ID, KM_ST_HW_FAULT);
    assert_int_equal((int16_t)reg_by_addr(0x17), 5);
    assert_int_equal(fx.fake.n_commits, c0 + 1u);
    assert_int_equal(kt_commit_value(&fx.fake.commits[c0], 0x17), 5);
    assert_int_equal(fx.fake.n_requests, 0);
    kt_ping_is(&fx, ID, KM_ST_HW_FAULT);
    /* restart = re-init: the latch is gone, both paths zero again */
    kt_reinit(&fx, kt_product_enc());
    kt_write(&fx, ID, 0x46, v2, 2);
    kt_write_u8(&fx, ID, 0x18, 0);
    assert_int_equal(fx.fake.n_requests, 2);
    assert_int_equal(fx.fake.requests[0].kind, KM_REQ_ZERO_POSITION);
    assert_int_equal(fx.fake.requests[1].kind, KM_REQ_ZERO_POSITION);
    kt_ping_is(&fx, ID, 0);
}

/* On a potentiometer product 0x18 = 0 is an ordinary increment of 0, so a
 * latched fault does not refuse it (§6, "Zeroing"). */
static void test_zeroing_pot_0x18_zero_is_an_increment_with_fault(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    km_live_t live = {0};
    live.hw_faults = 0x02;
    km_servo_set_live(&fx.s, &live);
    kt_write_u8(&fx, ID, 0x18, 0);
    kt_ping_is(&fx, ID, KM_ST_HW_FAULT);
    assert_int_equal(fx.fake.n_requests, 0);
    assert_int_equal(reg_by_addr(0x17), 0);
}

/* ---- "Motion preconditions": less motion with a fault latched ------------- */

/* §5.2 0x35, §4 bit 4 (issue 18 item 4): with a hardware fault latched, a
 * request for less motion reaches control and is not refused (0x6E = 0,
 * 0x6F = 0 on an encoder, 0x70 with its stop bit or with nothing to run,
 * 0x64 = 0/1); a request for more motion (0x6E != 0, 0x70 running, 0x65,
 * 0x64 = 2) is refused with bit 6 and sends nothing. */
static void test_s5_2_less_motion_passes_with_fault_latched(void **state)
{
    (void)state;
    static const struct {
        uint8_t addr, n, v[5];
        bool less;
    } cmds[] = {
        {0x6E, 2, {0x00, 0x00}, true},
        {0x6F, 2, {0x00, 0x00}, true},
        {0x70, 5, {0x80, 0x00, 0x00, 0x00, 0x00}, true}, /* stop, free after */
        {0x70, 5, {0x82, 0x00, 0x00, 0x00, 0x00}, true}, /* stop, brake after */
        {0x70, 5, {0x91, 0x32, 0x00, 0x20, 0x03}, true}, /* stop bit wins over its fields */
        {0x70, 5, {0x00, 0x00, 0x00, 0x00, 0x00}, true}, /* run on at PWM 0 */
        {0x70, 5, {0x10, 0x00, 0x00, 0xF4, 0x01}, true}, /* a run of 0 s */
        {0x64, 1, {0x00}, true},
        {0x64, 1, {0x01}, true},
        {0x6E, 2, {0x01, 0x00}, false},
        {0x6E, 2, {0x0C, 0xFE}, false}, /* -500 */
        {0x6F, 2, {0x1E, 0x00}, false},
        {0x70, 5, {0x10, 0x05, 0x00, 0xF4, 0x01}, false}, /* 0.5 s at PWM 500 */
        {0x65, 4, {0x00, 0x00, 0xE8, 0x03}, false},
        {0x64, 1, {0x02}, false},
    };
    for (unsigned i = 0; i < sizeof cmds / sizeof cmds[0]; i++) {
        kt_init(&fx, kt_product_enc(), ID);
        km_live_t live = {0};
        live.hw_faults = 0x04; /* temperature sensor */
        km_servo_set_live(&fx.s, &live);
        kt_write(&fx, ID, cmds[i].addr, cmds[i].v, cmds[i].n);
        if (cmds[i].less) {
            assert_int_equal(fx.fake.n_requests, 1);
            kt_ping_is(&fx, ID, KM_ST_HW_FAULT);
        } else {
            assert_int_equal(fx.fake.n_requests, 0);
            kt_ping_is(&fx, ID, KM_ST_HW_FAULT | KM_ST_FAILED);
        }
    }
    /* 0x5A = 1 (servo only) still refuses every motor command, a stop too:
     * no motor runs there, so there is nothing for it to stop */
    kt_init(&fx, kt_product_enc(), ID);
    kt_write_u8(&fx, ID, 0x5A, 1);
    motor_torque(ID, 0);
    assert_int_equal(fx.fake.n_requests, 0);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
}

/* ---- "Restart" -------------------------------------------------------------- */

/* After a valid restart nothing more runs until re-init: every later frame
 * (a write, pings own and super, a read, 0x04, 0x84, 0x83 listing us, 0x7F,
 * another restart) is not answered and changes not one byte. */
static void check_dead_after_restart(void)
{
    static const char *later[] = {
        "F9 FF 01 05 03 13 F4 01 EE",       /* write 0x13 = 500 */
        "F9 FF 01 02 01 FB",                /* ping */
        "F9 FF FD 02 01 FF",                /* super ping */
        "F9 FF 01 03 02 01 F8",             /* read 0x01 */
        "F9 FF 01 03 02 20 D9",             /* read of a reserved address */
        "F9 FF 01 04 04 64 02 90",          /* 0x04 torque on */
        "F9 FF FE 02 84 7B",                /* 0x84 */
        "F9 FF 01 02 84 78",                /* 0x84, own ID */
        "F9 FF FE 06 83 64 01 01 02 10",    /* 0x83 listing us */
        "F9 FF 01 03 7F 01 7B",             /* extension read */
        "F9 FF 01 03 82 13 66",             /* unknown command */
        "F9 FF 01 07 03 02 E1 E2 E3 E4 68", /* another restart */
    };
    assert_true(fx.s.restarting);
    assert_int_equal(fx.fake.restarts, 1);
    for (unsigned i = 0; i < sizeof later / sizeof later[0]; i++) {
        const km_servo_t before = fx.s;
        const kt_fake_t fake_before = fx.fake;
        kt_send_hex(&fx, later[i]);
        if (fx.reply.len != 0) {
            fail_msg("%s answered after a restart", later[i]);
        }
        assert_memory_equal(&before, &fx.s, sizeof before);
        assert_memory_equal(&fake_before, &fx.fake, sizeof fake_before);
    }
    kt_reinit(&fx, kt_product_pot()); /* the restart itself */
    assert_false(fx.s.restarting);
    kt_send_hex(&fx, "F9 FF 01 02 01 FB");
    kt_reply_is_hex(&fx, "F9 F5 01 02 00 FC");
}

static void test_restart_nothing_runs_after_it(void **state)
{
    (void)state;
    /* to the own ID at response level 1 (still no answer) */
    kt_init(&fx, kt_product_pot(), 1);
    kt_send_hex(&fx, "F9 FF 01 04 03 11 0A DC");
    kt_reply_is_hex(&fx, "F9 F5 01 02 00 FC");
    kt_send_hex(&fx, "F9 FF 01 07 03 02 E1 E2 E3 E4 68");
    kt_no_reply(&fx);
    check_dead_after_restart();
    /* broadcast */
    kt_init(&fx, kt_product_pot(), 1);
    const uint8_t magic[] = {0xE1, 0xE2, 0xE3, 0xE4};
    kt_write(&fx, KM_ID_BROADCAST, 0x02, magic, 4);
    kt_no_reply(&fx);
    check_dead_after_restart();
    /* buffered by 0x04, run by 0x84 */
    kt_init(&fx, kt_product_pot(), 1);
    kt_send_hex(&fx, "F9 FF 01 07 04 02 E1 E2 E3 E4 67");
    assert_int_equal(fx.fake.restarts, 0);
    kt_send_hex(&fx, "F9 FF FE 02 84 7B");
    kt_no_reply(&fx);
    check_dead_after_restart();
    /* a wrong magic is no restart: the servo keeps answering */
    kt_init(&fx, kt_product_pot(), 1);
    const uint8_t wrong[] = {0xE1, 0xE2, 0xE3, 0xE5};
    kt_write(&fx, 1, 0x02, wrong, 4);
    assert_false(fx.s.restarting);
    kt_send_hex(&fx, "F9 FF 01 02 01 FB");
    kt_reply_is_hex(&fx, "F9 F5 01 02 40 BC");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s5_1_0x01_status_read),
        cmocka_unit_test(test_s5_1_0x0A_model_text),
        cmocka_unit_test(test_s5_1_0x0B_protocol_version),
        cmocka_unit_test(test_s5_1_0x0C_firmware_version),
        cmocka_unit_test(test_s5_1_0x0F_id_change),
        cmocka_unit_test(test_s5_1_0x0F_id_change_commit_fails),
        cmocka_unit_test(test_s5_1_0x10_baud_change),
        cmocka_unit_test(test_s5_1_0x02_restart_broadcast),
        cmocka_unit_test(test_s5_1_0x03_userdata_reset_level1),
        cmocka_unit_test(test_s5_1_0x03_userdata_reset_level2),
        cmocka_unit_test(test_s5_1_0x03_userdata_reset_commit_fails),
        cmocka_unit_test(test_s5_commit_failure_keeps_old_value),
        cmocka_unit_test(test_s5_4_mirrors_follow),
        cmocka_unit_test(test_s5_4_0x64_torque_switch),
        cmocka_unit_test(test_s5_4_0x5A_control_mode),
        cmocka_unit_test(test_s5_1_0x18_increments_0x17),
        cmocka_unit_test(test_s5_1_0x18_zero_on_encoder),
        cmocka_unit_test(test_s5_2_0x36_write_one_to_clear),
        cmocka_unit_test(test_s5_3_0x46_0x4C_i16_or_i32),
        cmocka_unit_test(test_s5_3_live_reads),
        cmocka_unit_test(test_s6_encoder_only_commands_refused_on_pot),
        cmocka_unit_test(test_s5_3_0x46_zeroing_on_encoder),
        cmocka_unit_test(test_s5_4_servo_commands_requests),
        cmocka_unit_test(test_ext_0x7F_each_address),
        cmocka_unit_test(test_ext_0x7F_bad_address_or_length),
        cmocka_unit_test(test_ext_0x7F_super_id_slots),
        cmocka_unit_test(test_ext_0x7F_broadcast_no_answer),
        cmocka_unit_test(test_ext_0x7F_keeps_unreported_bits),
        cmocka_unit_test(test_s5_init_without_store_all_defaults),
        cmocka_unit_test(test_limits_runtime_not_above_maximum),
        cmocka_unit_test(test_limits_angle_min_below_max),
        cmocka_unit_test(test_limits_angle_window_both_write_orders),
        cmocka_unit_test(test_limits_angle_stored_contradicting_at_init),
        cmocka_unit_test(test_zeroing_refused_while_fault_latched),
        cmocka_unit_test(test_zeroing_pot_0x18_zero_is_an_increment_with_fault),
        cmocka_unit_test(test_s5_2_less_motion_passes_with_fault_latched),
        cmocka_unit_test(test_restart_nothing_runs_after_it),
    };
    return cmocka_run_group_tests_name("dispatch_commands", tests, NULL, NULL);
}
