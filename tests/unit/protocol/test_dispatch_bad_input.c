/* SPDX-License-Identifier: Apache-2.0 */
/* The bad-input catalog: each bad frame gets its defined outcome (docs/protocol.md
 * §3, §4, docs/protocol-decisions.md) AND changes nothing else: the register
 * file, the active baud, the sync buffer and the recorded commits, restarts
 * and requests are snapshot before and compared after. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_test_support.h"

#define ID 7
static kt_fx_t fx;

/* §5 addresses and access, written out from docs/protocol.md (not from the .def). */
typedef struct {
    uint8_t addr;
    uint8_t access;   /* 1 R, 2 W, 3 RW */
    uint8_t len;      /* value bytes of a write (shortest if several) */
    uint8_t len2;     /* longest valid write length (= len if one) */
    uint8_t valid[5]; /* a valid value of `len` bytes on the encoder product */
} spec_reg_t;

static const spec_reg_t spec_regs[] = {
    {0x01, 1, 0, 0, {0}},
    {0x02, 2, 4, 4, {0xE1, 0xE2, 0xE3, 0xE4}},
    {0x03, 2, 1, 1, {1}},
    {0x0A, 1, 0, 0, {0}},
    {0x0B, 1, 0, 0, {0}},
    {0x0C, 1, 0, 0, {0}},
    {0x0F, 3, 1, 1, {5}},
    {0x10, 3, 2, 2, {0x80, 0x04}},
    {0x11, 3, 1, 1, {0x0A}},
    {0x12, 3, 2, 2, {0xC8, 0x00}},
    {0x13, 3, 2, 2, {0xE8, 0x03}},
    {0x14, 3, 2, 2, {0xD0, 0x07}},
    {0x15, 3, 2, 2, {0x58, 0x02}},
    {0x16, 1, 0, 0, {0}},
    {0x17, 3, 2, 2, {0x00, 0x00}},
    {0x18, 2, 1, 1, {1}},
    {0x19, 3, 2, 2, {0x00, 0x00}},
    {0x1A, 3, 2, 2, {0x00, 0x00}},
    {0x32, 3, 1, 1, {0x0F}},
    {0x33, 3, 1, 1, {0x00}},
    {0x34, 3, 1, 1, {0x54}},
    {0x35, 1, 0, 0, {0}},
    {0x36, 3, 1, 1, {0x01}},
    {0x3C, 3, 2, 2, {14, 6}},
    {0x3D, 3, 2, 2, {60, 5}},
    {0x3E, 3, 3, 3, {0x08, 0x07, 20}},
    {0x3F, 3, 3, 3, {0x58, 0x02, 20}},
    {0x46, 3, 2, 4, {0x00, 0x00}},
    {0x47, 1, 0, 0, {0}},
    {0x48, 1, 0, 0, {0}},
    {0x49, 1, 0, 0, {0}},
    {0x4A, 1, 0, 0, {0}},
    {0x4B, 1, 0, 0, {0}},
    {0x4C, 1, 0, 0, {0}},
    {0x4D, 1, 0, 0, {0}},
    {0x5A, 3, 1, 1, {0}},
    {0x5B, 3, 2, 2, {0xE8, 0x03}},
    {0x5C, 3, 2, 2, {0xD0, 0x07}},
    {0x5D, 3, 2, 2, {0x58, 0x02}},
    {0x64, 3, 1, 1, {2}},
    {0x65, 2, 2, 4, {0x84, 0x03}},
    {0x66, 2, 2, 4, {0x84, 0x03}},
    {0x67, 2, 5, 5, {0x00, 0x84, 0x03, 0xE8, 0x03}},
    {0x68, 2, 2, 2, {0x84, 0x03}},
    {0x6E, 2, 2, 2, {0x64, 0x00}},
    {0x6F, 2, 2, 2, {0x64, 0x00}},
    {0x70, 2, 5, 5, {0x00, 0xE8, 0x03, 0x64, 0x00}},
};
#define N_SPEC (sizeof spec_regs / sizeof spec_regs[0])

static const spec_reg_t *spec_find(uint8_t addr)
{
    for (unsigned i = 0; i < N_SPEC; i++) {
        if (spec_regs[i].addr == addr) {
            return &spec_regs[i];
        }
    }
    return NULL;
}

/* A servo at response level 1 (0x11 bit 3), so every write answers. */
static void init_answering(const km_product_t *p)
{
    kt_init(&fx, p, ID);
    kt_write_u8(&fx, ID, 0x11, 0x0A);
    kt_reply_is_status(&fx, ID, 0);
}

/* §5: the table and the spec list hold the same addresses with the same access. */
static void test_s5_table_matches_spec_addresses(void **state)
{
    (void)state;
    assert_int_equal(KM_REG_COUNT, N_SPEC);
    for (unsigned a = 0; a < 256; a++) {
        const spec_reg_t *sp = spec_find((uint8_t)a);
        const int r = km_reg_find((uint8_t)a);
        if (!sp) {
            assert_int_equal(r, -1);
            continue;
        }
        assert_true(r >= 0);
        assert_int_equal(km_reg_table[r].access, sp->access);
    }
}

/* §4: a write of the wrong length (every writable register, one byte too few
 * and one too many; and 3 bytes for the 2-or-4 ones): bit 6, nothing changes.
 * The valid length with the same bytes is accepted, so the test can tell. */
static void test_s4_wrong_parameter_count_every_writable_register(void **state)
{
    (void)state;
    for (unsigned i = 0; i < N_SPEC; i++) {
        const spec_reg_t *sp = &spec_regs[i];
        if (!(sp->access & 2)) {
            continue;
        }
        uint8_t buf[8] = {0};
        memcpy(buf, sp->valid, sp->len);
        if (sp->len == 2 && sp->len2 == 4) { /* second field of 0x65/0x66/0x46 */
            buf[2] = 0x10;
            buf[3] = 0x00;
        }
        const unsigned bad[3] = {sp->len - 1u, sp->len2 + 1u, sp->len != sp->len2 ? 3u : sp->len2 + 1u};
        for (unsigned b = 0; b < 3; b++) {
            init_answering(kt_product_enc());
            kt_snap_t sn;
            kt_snap(&fx, &sn);
            kt_write(&fx, ID, sp->addr, buf, bad[b]);
            if (fx.reply.len != 6 || fx.reply.bytes[4] != KM_ST_FAILED) {
                fail_msg("0x%02X with %u bytes: answer status 0x%02X", sp->addr, bad[b],
                         fx.reply.len == 6 ? fx.reply.bytes[4] : 0xFFu);
            }
            kt_reply_is_status(&fx, ID, KM_ST_FAILED);
            kt_assert_unchanged(&fx, &sn);
        }
        /* The valid length is accepted (no bit 5/6). */
        init_answering(kt_product_enc());
        kt_write(&fx, ID, sp->addr, buf, sp->len);
        if (sp->addr == 0x02) {
            kt_no_reply(&fx);
            assert_int_equal(fx.fake.restarts, 1);
        } else {
            if (km_servo_status(&fx.s) & (KM_ST_FAILED | KM_ST_EXCEPTION)) {
                fail_msg("valid write of 0x%02X refused", sp->addr);
            }
            /* 0x03 resets 0x11 to response level 0 before the answer is due. */
            if (sp->addr != 0x03) {
                kt_reply_is_status(&fx, ID, 0); /* 0x0F too: the old ID (§3) */
            }
        }
    }
}

/* §1: 251, 252 and 255 are no servo IDs: such frames reach nothing, whatever
 * the command; handle() changes not one byte of the servo. */
static void test_s1_invalid_ids_reach_nothing(void **state)
{
    (void)state;
    static const uint8_t ids[] = {251, 252, 255};
    static const uint8_t cmds[] = {0x01, 0x02, 0x03, 0x04, 0x84, 0x83, 0x82, 0x78, 0x7E, 0x7F};
    kt_init(&fx, kt_product_pot(), ID);
    kt_write_u8(&fx, ID, 0x64, 9); /* leaves bit 6 pending */
    static const uint8_t sync_body[] = {0x64, 0x02};
    kt_send(&fx, ID, 0x04, sync_body, 2); /* and a full sync buffer */
    assert_true(fx.s.sync.full);
    for (unsigned i = 0; i < sizeof ids; i++) {
        for (unsigned c = 0; c < sizeof cmds; c++) {
            const uint8_t body[] = {0x64, 0x01, ID, 0x02};
            const unsigned n = cmds[c] == 0x01 || cmds[c] == 0x84 ? 0u : (cmds[c] == 0x02 ? 1u : 4u);
            km_servo_t before = fx.s;
            kt_fake_t fake_before = fx.fake;
            kt_send(&fx, ids[i], cmds[c], body, n);
            kt_no_reply(&fx);
            assert_memory_equal(&before, &fx.s, sizeof before);
            assert_memory_equal(&fake_before, &fx.fake, sizeof fake_before);
        }
    }
}

/* §4: every address not in §5, read: bit 5 in the short response. */
static void test_s4_reserved_addresses_read(void **state)
{
    (void)state;
    for (unsigned a = 0; a < 256; a++) {
        if (spec_find((uint8_t)a)) {
            continue;
        }
        kt_init(&fx, kt_product_pot(), ID);
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        kt_read(&fx, ID, (uint8_t)a);
        kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
        kt_assert_unchanged(&fx, &sn);
    }
}

/* §4: every address not in §5, written (1 and 2 bytes): bit 5, nothing changes. */
static void test_s4_reserved_addresses_write(void **state)
{
    (void)state;
    for (unsigned a = 0; a < 256; a++) {
        if (spec_find((uint8_t)a)) {
            continue;
        }
        for (unsigned n = 1; n <= 2; n++) {
            init_answering(kt_product_pot());
            kt_snap_t sn;
            kt_snap(&fx, &sn);
            const uint8_t v[2] = {0x01, 0x00};
            kt_write(&fx, ID, (uint8_t)a, v, n);
            kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
            kt_assert_unchanged(&fx, &sn);
        }
    }
}

/* §4: a read of a write-only register: bit 5, short response. */
static void test_s4_read_of_write_only(void **state)
{
    (void)state;
    for (unsigned i = 0; i < N_SPEC; i++) {
        if (spec_regs[i].access != 2) {
            continue;
        }
        kt_init(&fx, kt_product_pot(), ID);
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        kt_read(&fx, ID, spec_regs[i].addr);
        kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
        kt_assert_unchanged(&fx, &sn);
    }
}

/* §4: a write of a read-only register (0x16 included): bit 5, nothing changes. */
static void test_s4_write_of_read_only(void **state)
{
    (void)state;
    bool saw_0x16 = false;
    for (unsigned i = 0; i < N_SPEC; i++) {
        if (spec_regs[i].access != 1) {
            continue;
        }
        saw_0x16 |= spec_regs[i].addr == 0x16;
        for (unsigned n = 1; n <= 4; n++) {
            init_answering(kt_product_pot());
            kt_snap_t sn;
            kt_snap(&fx, &sn);
            const uint8_t v[4] = {0x05, 0x00, 0x00, 0x00};
            kt_write(&fx, ID, spec_regs[i].addr, v, n);
            kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
            kt_assert_unchanged(&fx, &sn);
        }
    }
    assert_true(saw_0x16);
}

/* §4: out-of-range values: bit 6, nothing changes. */
static void test_s4_out_of_range_values(void **state)
{
    (void)state;
    static const struct {
        uint8_t addr, n, v[3];
    } cases[] = {
        {0x0F, 1, {251}},        /* IDs 0..250 */
        {0x13, 2, {0xE9, 0x03}}, /* 1001 > PWM 1000 */
        {0x64, 1, {4}},          /* 0x64: 0..3 */
        {0x64, 1, {5}},          /* 5 is set by the servo, not writable */
        {0x5A, 1, {3}},          /* 0x5A: 0..2 */
        {0x03, 1, {0}},          /* 0x03: 1 or 2 */
        {0x03, 1, {3}},
        {0x18, 1, {101}}, /* 0x18: -100..100 */
        {0x18, 1, {(uint8_t)-101}},
        {0x6E, 2, {0xE9, 0x03}}, /* 0x6E: -1000..1000 */
    };
    for (unsigned i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        init_answering(kt_product_pot());
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        kt_write(&fx, ID, cases[i].addr, cases[i].v, cases[i].n);
        kt_reply_is_status(&fx, ID, KM_ST_FAILED);
        kt_assert_unchanged(&fx, &sn);
    }
}

/* §3: 0x84 with nothing buffered: nothing happens, and no error. */
static void test_s3_sync_execute_without_sync_write(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_send_hex(&fx, "F9 FF FE 02 84 7B");
    kt_no_reply(&fx);
    kt_assert_unchanged(&fx, &sn);
    assert_int_equal(km_servo_status(&fx.s), 0);
}

/* §3: any other command addressed to this servo between 0x04 and 0x84 clears
 * the buffer (a ping, a read, a write, each to own, broadcast or super ID). */
static void test_s3_sync_write_cleared_by_other_command(void **state)
{
    (void)state;
    static const struct {
        uint8_t id, cmd, n, body[2];
    } others[] = {
        {ID, 0x01, 0, {0}},          {ID, 0x02, 1, {0x13}},
        {ID, 0x03, 2, {0x11, 0x02}}, {KM_ID_BROADCAST, 0x03, 2, {0x11, 0x02}},
        {KM_ID_SUPER, 0x01, 0, {0}}, {KM_ID_SUPER, 0x02, 1, {0x13}},
    };
    for (unsigned i = 0; i < sizeof others / sizeof others[0]; i++) {
        kt_init(&fx, kt_product_pot(), ID);
        static const uint8_t sync_body[] = {0x64, 0x02};
        kt_send(&fx, ID, 0x04, sync_body, 2);
        kt_send(&fx, others[i].id, others[i].cmd, others[i].body, others[i].n);
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        kt_send_hex(&fx, "F9 FF FE 02 84 7B");
        kt_assert_unchanged(&fx, &sn);
        assert_int_equal(fx.fake.n_requests, 0);
        assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_SWITCH), 3);
    }
}

/* §3 Reading: a 0x04 for another ID does not clear ours; 0x84 executes ours. */
static void test_s3_sync_write_other_id_keeps_ours(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    static const uint8_t mine[] = {0x64, 0x02};
    static const uint8_t theirs[] = {0x64, 0x00};
    kt_send(&fx, ID, 0x04, mine, 2);
    kt_send(&fx, ID + 1, 0x04, theirs, 2);
    kt_send(&fx, ID + 1, 0x03, theirs, 2);
    assert_int_equal(fx.fake.n_requests, 0);
    kt_send_hex(&fx, "F9 FF FE 02 84 7B");
    assert_int_equal(fx.fake.n_requests, 1);
    assert_int_equal(fx.fake.requests[0].kind, KM_REQ_TORQUE);
    assert_int_equal(fx.fake.requests[0].u.torque, 2);
}

/* §3: a second 0x04 overwrites the buffer. */
static void test_s3_sync_write_second_overwrites(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    static const uint8_t first[] = {0x64, 0x02};
    static const uint8_t second[] = {0x64, 0x01};
    kt_send(&fx, ID, 0x04, first, 2);
    kt_send(&fx, ID, 0x04, second, 2);
    kt_send_hex(&fx, "F9 FF FE 02 84 7B");
    assert_int_equal(fx.fake.n_requests, 1);
    assert_int_equal(fx.fake.requests[0].u.torque, 1);
}

/* Sync write 0x04 of an unknown or read-only address: bit 5 at once, nothing buffered. */
static void test_s3_sync_write_bad_address(void **state)
{
    (void)state;
    static const uint8_t addrs[] = {0x00, 0x20, 0x16, 0x01};
    for (unsigned i = 0; i < sizeof addrs; i++) {
        kt_init(&fx, kt_product_pot(), ID);
        const uint8_t body[] = {addrs[i], 0x01, 0x00};
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        kt_send(&fx, ID, 0x04, body, 3);
        kt_no_reply(&fx);
        assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION);
        kt_send_hex(&fx, "F9 FF FE 02 84 7B");
        sn.unreported |= KM_ST_EXCEPTION; /* 0x04 has no answer: the next ping reports it */
        kt_assert_unchanged(&fx, &sn);
    }
}

/* "Multi-ID write" and §4: malformed entries (k wrong for the address,
 * parameter count not a multiple of k+1, no entries) are a bad value: every
 * servo sets bit 6; an address 0x83 does not allow is an unsupported
 * address: every servo sets bit 5. Nothing runs either way; the bit waits
 * for the next ping (no answer), which reports it once. */
static void test_s3_multi_id_malformed_and_unsupported_address(void **state)
{
    (void)state;
    static const struct {
        uint8_t n, body[12];
        uint8_t bit;
    } bad[] = {
        {6, {0x64, 0x02, ID, 0x02, 0x00, 0x00}, KM_ST_FAILED},         /* k 2 for 0x64 */
        {5, {0x64, 0x01, ID, 0x02, 0x03}, KM_ST_FAILED},               /* 3 params, k+1 = 2 */
        {2, {0x64, 0x01}, KM_ST_FAILED},                               /* no entries */
        {5, {0x65, 0x03, ID, 0x84, 0x03}, KM_ST_FAILED},               /* k 3 for 0x65 */
        {7, {0x65, 0x02, ID, 0x84, 0x03, ID + 1, 0x00}, KM_ST_FAILED}, /* truncated */
        {4, {0x68, 0x04, ID, 0x05}, KM_ST_FAILED},                     /* k 4 for 0x68 */
        {4, {0x13, 0x01, ID, 0x05}, KM_ST_EXCEPTION},                  /* 0x13 not allowed */
        {4, {0x67, 0x01, ID, 0x05}, KM_ST_EXCEPTION},                  /* 0x67 not allowed */
        {4, {0x20, 0x01, ID, 0x05}, KM_ST_EXCEPTION},                  /* reserved address */
        {6, {0x70, 0x01, ID, 0x05, ID + 1, 0x05}, KM_ST_EXCEPTION},    /* 0x70 not allowed */
    };
    for (unsigned i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        kt_init(&fx, kt_product_pot(), ID);
        static const uint8_t sync_body[] = {0x13, 0xF4, 0x01};
        kt_send(&fx, ID, 0x04, sync_body, sizeof sync_body); /* every servo drops its buffer */
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        kt_send(&fx, KM_ID_BROADCAST, 0x83, bad[i].body, bad[i].n);
        kt_no_reply(&fx);
        sn.sync_full = false;
        sn.unreported |= bad[i].bit;
        kt_assert_unchanged(&fx, &sn);
        if (km_servo_status(&fx.s) != bad[i].bit) {
            fail_msg("case %u: status 0x%02X, want 0x%02X", i, km_servo_status(&fx.s), bad[i].bit);
        }
        kt_ping_is(&fx, ID, bad[i].bit);
        kt_ping_is(&fx, ID, 0);
    }
}

/* "Multi-ID write": an allowed address without its `k` byte is malformed
 * (`k` not allowed for the address): bit 6, like the other malformed
 * frames -- the address itself is one 0x83 supports. */
static void test_s3_multi_id_missing_k_is_malformed(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_send_hex(&fx, "F9 FF FE 03 83 64 17");
    kt_no_reply(&fx);
    sn.unreported |= KM_ST_FAILED;
    kt_assert_unchanged(&fx, &sn);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
}

/* "Multi-ID write" sent to the servo's own ID (not broadcast): bit 5, nothing runs. */
static void test_s3_multi_id_to_own_id(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t body[] = {0x64, 0x01, ID, 0x02};
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_send(&fx, ID, 0x83, body, sizeof body);
    kt_no_reply(&fx);
    sn.unreported |= KM_ST_EXCEPTION; /* no answer: the next ping reports it */
    kt_assert_unchanged(&fx, &sn);
    assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION);
    kt_ping_is(&fx, ID, KM_ST_EXCEPTION);
    kt_ping_is(&fx, ID, 0);
}

/* §3 restart: wrong magic or wrong length: no restart, bit 6. */
static void test_s3_restart_wrong_magic_or_length(void **state)
{
    (void)state;
    static const struct {
        uint8_t n, v[5];
    } bad[] = {
        {4, {0xE1, 0xE2, 0xE3, 0xE5}},
        {4, {0xE4, 0xE3, 0xE2, 0xE1}},
        {3, {0xE1, 0xE2, 0xE3}},
        {5, {0xE1, 0xE2, 0xE3, 0xE4, 0x00}},
        {0, {0}},
    };
    for (unsigned i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        init_answering(kt_product_pot());
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        kt_write(&fx, ID, 0x02, bad[i].v, bad[i].n);
        kt_reply_is_status(&fx, ID, KM_ST_FAILED);
        kt_assert_unchanged(&fx, &sn);
    }
}

/* §3: read with the broadcast ID: nobody answers, nothing changes (the
 * unreported bits included: a read of a readable register has no bad
 * outcome; the read of an address the servo does not have is in
 * test_dispatch_status.c, rule 5). */
static void test_s3_read_broadcast_no_answer(void **state)
{
    (void)state;
    static const uint8_t addrs[] = {0x01, 0x0B, 0x13, 0x46, 0x0A, 0x35};
    for (unsigned i = 0; i < sizeof addrs; i++) {
        kt_init(&fx, kt_product_pot(), ID);
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        kt_read(&fx, KM_ID_BROADCAST, addrs[i]);
        kt_no_reply(&fx);
        kt_assert_unchanged(&fx, &sn);
    }
}

/* §3/§7 and "Malformed frames": 0x78 (without the firmware's update op),
 * 0x7E and every other byte that is not a command of this firmware: bit 5,
 * no answer, nothing else changes; the next ping reports it once. All 248
 * of them, so a command byte the dispatcher's table confuses with another
 * (it looks commands up by a few bits) would show. (0x7F is the extension
 * read: test_dispatch_commands.c; 0x82 the multi-ID read:
 * test_dispatch_multi_read.c.) */
static void test_s3_unsupported_commands(void **state)
{
    (void)state;
    static const uint8_t known[] = {0x01, 0x02, 0x03, 0x04, 0x7F, 0x82, 0x83, 0x84};
    uint8_t cmds[256];
    unsigned n = 0;
    for (unsigned c = 0; c < 256u; c++) {
        if (memchr(known, (int)c, sizeof known) == NULL) {
            cmds[n++] = (uint8_t)c;
        }
    }
    assert_int_equal(n, 248);
    for (unsigned i = 0; i < n; i++) {
        init_answering(kt_product_pot());
        kt_snap_t sn;
        kt_snap(&fx, &sn);
        const uint8_t body[] = {0x13, 0x01};
        kt_send(&fx, ID, cmds[i], body, sizeof body);
        kt_no_reply(&fx);
        sn.unreported |= KM_ST_EXCEPTION;
        kt_assert_unchanged(&fx, &sn);
        assert_int_equal(km_servo_status(&fx.s), KM_ST_EXCEPTION);
        kt_ping(&fx, ID); /* the next ping reports it, then it clears */
        kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
        kt_ping(&fx, ID);
        kt_reply_is_status(&fx, ID, 0);
    }
}

/* "Extension command 0x7F": 0x0D, once this firmware's extension register,
 * is a reserved address again: read and write are bit 5 with the short
 * response (level 1), nothing changes. */
static void test_s4_0x0D_reserved_again(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), 1);
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_send_hex(&fx, "F9 FF 01 03 02 0D EC");
    kt_reply_is_hex(&fx, "F9 F5 01 02 20 DC");
    kt_assert_unchanged(&fx, &sn);
    kt_send_hex(&fx, "F9 FF 01 04 03 11 0A DC"); /* level 1 */
    kt_reply_is_hex(&fx, "F9 F5 01 02 00 FC");
    kt_snap(&fx, &sn);
    kt_send_hex(&fx, "F9 FF 01 04 03 0D 00 EA");
    kt_reply_is_hex(&fx, "F9 F5 01 02 20 DC");
    kt_assert_unchanged(&fx, &sn);
}

/* §3 ping takes no parameters: extra bytes answer with bit 5. */
static void test_s3_ping_with_extra_bytes(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    const uint8_t extra[] = {0x00};
    kt_send(&fx, ID, 0x01, extra, 1);
    kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
    kt_assert_unchanged(&fx, &sn);
}

/* "Malformed frames": a read with extra bytes, a write without address. */
static void test_s3_read_extra_bytes_and_write_without_address(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    const uint8_t body[] = {0x13, 0x00};
    kt_send(&fx, ID, 0x02, body, 2);
    kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
    kt_assert_unchanged(&fx, &sn);
    kt_write_u8(&fx, ID, 0x11, 0x0A);
    kt_snap(&fx, &sn);
    kt_send(&fx, ID, 0x03, NULL, 0);
    kt_reply_is_status(&fx, ID, KM_ST_EXCEPTION);
    kt_assert_unchanged(&fx, &sn);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s5_table_matches_spec_addresses),
        cmocka_unit_test(test_s4_wrong_parameter_count_every_writable_register),
        cmocka_unit_test(test_s1_invalid_ids_reach_nothing),
        cmocka_unit_test(test_s4_reserved_addresses_read),
        cmocka_unit_test(test_s4_reserved_addresses_write),
        cmocka_unit_test(test_s4_read_of_write_only),
        cmocka_unit_test(test_s4_write_of_read_only),
        cmocka_unit_test(test_s4_out_of_range_values),
        cmocka_unit_test(test_s3_sync_execute_without_sync_write),
        cmocka_unit_test(test_s3_sync_write_cleared_by_other_command),
        cmocka_unit_test(test_s3_sync_write_other_id_keeps_ours),
        cmocka_unit_test(test_s3_sync_write_second_overwrites),
        cmocka_unit_test(test_s3_sync_write_bad_address),
        cmocka_unit_test(test_s3_multi_id_malformed_and_unsupported_address),
        cmocka_unit_test(test_s3_multi_id_missing_k_is_malformed),
        cmocka_unit_test(test_s3_multi_id_to_own_id),
        cmocka_unit_test(test_s3_restart_wrong_magic_or_length),
        cmocka_unit_test(test_s3_read_broadcast_no_answer),
        cmocka_unit_test(test_s3_unsupported_commands),
        cmocka_unit_test(test_s4_0x0D_reserved_again),
        cmocka_unit_test(test_s3_ping_with_extra_bytes),
        cmocka_unit_test(test_s3_read_extra_bytes_and_write_without_address),
    };
    return cmocka_run_group_tests_name("dispatch_bad_input", tests, NULL, NULL);
}
