/* PROTOCOL.md §3 commands and the §5 registers whose write or read is more
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

/* ID change whose commit fails: bit 6, the old ID stays. */
static void test_s5_1_0x0F_id_change_commit_fails(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    answering();
    fx.fake.fail_next_commit = true;
    kt_write_u8(&fx, ID, 0x0F, 42);
    kt_reply_is_status(&fx, ID, KM_ST_FAILED);
    kt_ping(&fx, 42);
    kt_no_reply(&fx);
    kt_ping(&fx, ID); /* the previous command failed: reported once more, then cleared */
    kt_reply_is_status(&fx, ID, KM_ST_FAILED);
    kt_ping(&fx, ID);
    kt_reply_is_status(&fx, ID, 0);
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

/* Expected defaults from PROTOCOL.md §5 ("—" = the product's value). */
static uint32_t spec_default(uint8_t addr, const km_product_t *p)
{
    switch (addr) {
    case 0x0F: return 0;
    case 0x10: return 1152;
    case 0x11: return 0x02;
    case 0x12: return 200;
    case 0x13: return 1000;
    case 0x14: return p->max_current_ma;
    case 0x15: return p->max_speed_dps;
    case 0x16: return (uint16_t)p->zero_offset1;
    case 0x17: return 0;
    case 0x19: return (uint16_t)p->angle_min;
    case 0x1A: return (uint16_t)p->angle_max;
    case 0x32: return 0x0F;
    case 0x33: return 0x00;
    case 0x34: return 0x54;
    case 0x3C: return (uint32_t)p->voltage_high_v | ((uint32_t)p->voltage_low_v << 8);
    case 0x3D: return 60u | (5u << 8);
    case 0x3E: return (uint32_t)p->current_threshold_ma | (20u << 16);
    case 0x3F: return 600u | (20u << 16);
    default: fail_msg("no default for 0x%02X", addr); return 0;
    }
}

static const uint8_t persisted_addrs[] = {0x0F, 0x10, 0x11, 0x12, 0x13, 0x14, 0x15, 0x16, 0x17,
                                          0x19, 0x1A, 0x32, 0x33, 0x34, 0x3C, 0x3D, 0x3E, 0x3F};

/* A servo whose user data all differ from the defaults, 0x16 included
 * (factory calibration handed over by the store). */
static void init_changed(void)
{
    kt_init(&fx, kt_product_pot(), ID);
    static const struct { uint8_t addr; uint32_t v; } changed[] = {
        {0x10, 10000}, {0x11, 0x0B}, {0x12, 300}, {0x13, 500}, {0x14, 1000}, {0x15, 300},
        {0x16, 99}, {0x17, 55}, {0x19, 0xFC18 /* -1000 */}, {0x1A, 1000}, {0x32, 0x03},
        {0x33, 0x01}, {0x34, 0x00}, {0x3C, 12u | (7u << 8)}, {0x3D, 70u | (10u << 8)},
        {0x3E, 1000u | (5u << 16)}, {0x3F, 500u | (5u << 16)},
    };
    unsigned k = 0;
    for (unsigned j = 0; j < KM_REG_COUNT; j++) {
        if (!km_reg_table[j].persisted) continue;
        for (unsigned c = 0; c < sizeof changed / sizeof changed[0]; c++) {
            if (changed[c].addr == km_reg_table[j].addr) fx.persisted[k] = changed[c].v;
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

/* Level 2: everything, ID, baud, 0x16 (back to the product's factory value)
 * and 0x17 included. */
static void test_s5_1_0x03_userdata_reset_level2(void **state)
{
    (void)state;
    init_changed();
    kt_write_u8(&fx, ID, 0x03, 2);
    kt_no_reply(&fx); /* 0x11 back to level 0 */
    assert_int_equal(fx.fake.n_commits, 1);
    const kt_commit_t *c = &fx.fake.commits[0];
    assert_int_equal(c->n, sizeof persisted_addrs);
    for (unsigned i = 0; i < sizeof persisted_addrs; i++) {
        const uint8_t a = persisted_addrs[i];
        assert_int_equal(kt_commit_value(c, a), spec_default(a, kt_product_pot()));
        assert_int_equal(reg_by_addr(a), spec_default(a, kt_product_pot()));
    }
    assert_int_equal(km_servo_id(&fx.s), 0);
    assert_int_equal(reg_by_addr(0x16), 37);
    assert_int_equal(reg_by_addr(0x5B), 1000);
    assert_int_equal(km_servo_active_baud(&fx.s), 1000000); /* baud applies at restart */
}

/* A reset whose commit fails changes nothing, bit 6. */
static void test_s5_1_0x03_userdata_reset_commit_fails(void **state)
{
    (void)state;
    init_changed();
    fx.fake.fail_next_commit = true;
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_write_u8(&fx, ID, 0x03, 2);
    sn.n_commits++; /* the refused attempt */
    kt_assert_unchanged(&fx, &sn);
    assert_false(fx.fake.commits[0].accepted);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
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
        assert_int_equal(fx.fake.requests[n - 1].kind, KM_REQ_TORQUE_SWITCH);
        assert_int_equal(fx.fake.requests[n - 1].u.u8, v);
        move_time(ID);
        assert_int_equal(fx.fake.n_requests, n);
        assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
        assert_int_equal(reg_by_addr(0x64), v);
    }
    kt_write_u8(&fx, ID, 0x64, 5);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
    assert_int_equal(reg_by_addr(0x64), 1);
    km_servo_set_torque_switch(&fx.s, 5); /* control, after a protection */
    kt_read(&fx, ID, 0x64);
    assert_int_equal(kt_read_le(&fx, 0x64), 5);
    const unsigned n = fx.fake.n_requests;
    move_time(ID);
    assert_int_equal(fx.fake.n_requests, n);
    kt_write_u8(&fx, ID, 0x64, 2);
    move_time(ID);
    assert_int_equal(fx.fake.n_requests, n + 2);
    assert_int_equal(fx.fake.requests[n + 1].kind, KM_REQ_MOVE_TIME);
    assert_int_equal(reg_by_addr(0x64), 2);
}

/* §5.4 0x5A: 1 servo only refuses motor commands, 2 motor only refuses servo
 * commands; switching to 2 is refused while running with torque on. */
static void test_s5_4_0x5A_control_mode(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_write_u8(&fx, ID, 0x5A, 1);
    motor_torque(ID, 300);
    assert_int_equal(fx.fake.n_requests, 0);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
    move_time(ID);
    assert_int_equal(fx.fake.n_requests, 1);
    kt_write_u8(&fx, ID, 0x5A, 2); /* idle: allowed */
    assert_int_equal(reg_by_addr(0x5A), 2);
    move_time(ID);
    assert_int_equal(fx.fake.n_requests, 1);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
    motor_torque(ID, -300);
    assert_int_equal(fx.fake.n_requests, 2);
    assert_int_equal(fx.fake.requests[1].kind, KM_REQ_MOTOR_TORQUE);
    assert_int_equal(fx.fake.requests[1].u.i16, -300);
    kt_write_u8(&fx, ID, 0x5A, 0);
    km_live_t live = {0};
    live.running = true;
    km_servo_set_live(&fx.s, &live);
    kt_write_u8(&fx, ID, 0x64, 2);
    kt_write_u8(&fx, ID, 0x5A, 2); /* running with torque on: refused */
    assert_int_equal(km_servo_status(&fx.s) & KM_ST_FAILED, KM_ST_FAILED);
    assert_int_equal(reg_by_addr(0x5A), 0);
    kt_write_u8(&fx, ID, 0x64, 0);
    kt_write_u8(&fx, ID, 0x5A, 2); /* torque off: allowed */
    assert_int_equal(km_servo_status(&fx.s) & KM_ST_FAILED, 0);
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
    kt_assert_unchanged(&fx, &sn);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
    kt_write_u16(&fx, ID, 0x17, (uint16_t)(int16_t)-max);
    kt_snap(&fx, &sn);
    kt_write_u8(&fx, ID, 0x18, (uint8_t)-1);
    kt_assert_unchanged(&fx, &sn);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
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

/* §5.2 0x36: write 1 to a bit to clear that protection: a request, nothing stored. */
static void test_s5_2_0x36_write_one_to_clear(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_write_u8(&fx, ID, 0x36, 0x09);
    assert_int_equal(fx.fake.n_requests, 1);
    assert_int_equal(fx.fake.requests[0].kind, KM_REQ_PROTECTION_CLEAR);
    assert_int_equal(fx.fake.requests[0].u.u8, 0x09);
    assert_int_equal(fx.fake.n_commits, 0);
    kt_write_u8(&fx, ID, 0x36, 0x10);
    assert_int_equal(fx.fake.n_requests, 1);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
}

static void read_pos(uint8_t addr, int32_t v)
{
    km_live_t live = {0};
    if (addr == 0x46) live.position = v; else live.deviation = v;
    km_servo_set_live(&fx.s, &live);
    kt_read(&fx, ID, addr);
    uint8_t want[4];
    const unsigned n = (v >= -32768 && v <= 32767) ? 2u : 4u;
    for (unsigned i = 0; i < n; i++) want[i] = (uint8_t)((uint32_t)v >> (8u * i));
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
    static const struct { uint8_t addr; int16_t v; } i16s[] = {
        {0x47, -120}, {0x48, 1500}, {0x49, 999}, {0x4A, 41}, {0x4B, 12100}};
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
    static const struct { uint8_t addr, n, v[5]; } cmds[] = {
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
    assert_int_equal(fx.fake.requests[0].kind, KM_REQ_MOTOR_ADVANCED);
    assert_int_equal(fx.fake.requests[0].u.adv.control, 0x10);
    assert_int_equal(fx.fake.requests[0].u.adv.p1, 20);
    assert_int_equal(fx.fake.requests[0].u.adv.p2, 500);
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
    assert_int_equal(fx.fake.requests[0].kind, KM_REQ_MOVE_SPEED);
    assert_int_equal(fx.fake.requests[0].u.move.target, -900);
    assert_int_equal(fx.fake.requests[0].u.move.param, 300);
    assert_int_equal(fx.fake.requests[1].kind, KM_REQ_INTERPOLATE);
    assert_int_equal(fx.fake.requests[1].u.move.target, 10);
    assert_int_equal(fx.fake.requests[2].kind, KM_REQ_SERVO_ADVANCED);
    assert_int_equal(fx.fake.requests[2].u.adv.control, 0x12);
    assert_int_equal(fx.fake.requests[2].u.adv.p1, 100);
    assert_int_equal(fx.fake.requests[2].u.adv.p2, 500);
    const uint8_t bad[] = {0x12, 0x64, 0x00, 0xE9, 0x03}; /* max PWM 1001 */
    kt_write(&fx, ID, 0x67, bad, 5);
    assert_int_equal(fx.fake.n_requests, 3);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_FAILED);
}

/* 0x0D (this firmware's extension, docs/protocol-decisions.md): where the
 * user data came from at boot; read-only. */
static void test_s7_0x0D_userdata_source(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t loaded[1] = {KM_USERDATA_LOADED};
    kt_read(&fx, ID, 0x0D);
    kt_reply_is_read(&fx, ID, 0x0D, loaded, 1);
    km_servo_set_userdata_source(&fx.s, KM_USERDATA_DEFAULTS_INVALID);
    const uint8_t invalid[1] = {3};
    kt_read(&fx, ID, 0x0D);
    kt_reply_is_read(&fx, ID, 0x0D, invalid, 1);
    kt_write_u8(&fx, ID, 0x0D, 0);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION); /* read-only: bit 5 */
    kt_read(&fx, ID, 0x0D);
    kt_reply_is_read(&fx, ID, 0x0D, invalid, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s7_0x0D_userdata_source),
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
    };
    return cmocka_run_group_tests_name("dispatch_commands", tests, NULL, NULL);
}
