/* SPDX-License-Identifier: Apache-2.0 */
/* Shared helpers for the dispatcher tests (header-only: tests/support/ is on
 * the include path, nothing here is compiled on its own).
 *
 *  - two test products (potentiometer and encoder, docs/protocol.md §6);
 *  - a recording fake of km_servo_ops_t: every commit (addresses and values,
 *    accepted or refused), every restart and every typed request; it can be
 *    told to refuse the next commit;
 *  - kt_frame_from_hex(): a whole §2 command frame as hex text -> km_frame_t,
 *    after checking the header, the length byte and the checksum (computed
 *    here from the §2 rule, independently of protocol/), so every worked
 *    frame used by a test is itself verified;
 *  - a fixture (servo + fake + last reply), senders and a snapshot of
 *    everything a bad input must leave alone (the unreported status bits
 *    included: docs/protocol-decisions.md "One life cycle for bits 5 and 6").
 *
 * Include after <setjmp.h> <stdarg.h> <stddef.h> <cmocka.h>. */
#ifndef KM_TEST_SUPPORT_H
#define KM_TEST_SUPPORT_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "km_frame.h"
#include "km_product.h"
#include "km_registers.h"
#include "km_servo.h"

/* ---- products ----------------------------------------------------------- */

static inline const km_product_t *kt_product_pot(void)
{
    static const km_product_t p = {
        .model = "KM-TEST-POT",
        .firmware_version = 0x52111002u, /* §5.1 0x0C example: boot 5.2, hw 1.1, sw 1.0.02 */
        .variant = KM_VARIANT_POTENTIOMETER,
        .max_current_ma = 2000,
        .max_speed_dps = 600,
        .zero_offset1 = 37,
        .angle_min = -1350,
        .angle_max = 1350,
        .voltage_high_v = 14,
        .voltage_low_v = 6,
        .current_threshold_ma = 1800,
        .baud_min_100 = 96,
        .baud_max_100 = 10000,
        .current_max_ma = 3000,
        .speed_max_dps = 1000,
        .travel_min = -1350,
        .travel_max = 1350,
        .pos_read_min = -1575,
        .pos_read_max = 1575,
        .zero_offset2_max = 300,
        .voltage_max_v = 30,
    };
    return &p;
}

static inline const km_product_t *kt_product_enc(void)
{
    static const km_product_t p = {
        .model = "KM-TEST-ENCODER-X", /* 17 characters: answered as 16 */
        .firmware_version = 0x00201003u,
        .variant = KM_VARIANT_ENCODER,
        .max_current_ma = 4000,
        .max_speed_dps = 900,
        .zero_offset1 = -12,
        .angle_min = 0,
        .angle_max = 0,
        .voltage_high_v = 26,
        .voltage_low_v = 9,
        .current_threshold_ma = 3500,
        .baud_min_100 = 96,
        .baud_max_100 = 10000,
        .current_max_ma = 5000,
        .speed_max_dps = 1500,
        .travel_min = -32000,
        .travel_max = 32000,
        .zero_offset2_max = 1800,
        .voltage_max_v = 40,
    };
    return &p;
}

/* ---- recording fake of km_servo_ops_t ------------------------------------ */

#define KT_MAX_COMMITS 16
#define KT_MAX_COMMIT_REGS 48
#define KT_MAX_REQUESTS 32

typedef struct {
    uint8_t n;
    bool accepted;
    uint8_t addrs[KT_MAX_COMMIT_REGS];
    uint32_t values[KT_MAX_COMMIT_REGS];
} kt_commit_t;

typedef struct {
    kt_commit_t commits[KT_MAX_COMMITS];
    unsigned n_commits; /* every call, accepted or not */
    unsigned restarts;
    km_request_t requests[KT_MAX_REQUESTS];
    unsigned n_requests;
    bool fail_next_commit;
    bool refuse_requests; /* control answers "refused" (recorded all the same) */
} kt_fake_t;

static inline bool kt_fake_commit(void *ctx, const uint8_t *addrs, const uint32_t *values, uint8_t n)
{
    kt_fake_t *f = ctx;
    assert_true(f->n_commits < KT_MAX_COMMITS);
    assert_true(n <= KT_MAX_COMMIT_REGS);
    kt_commit_t *c = &f->commits[f->n_commits++];
    c->n = n;
    memcpy(c->addrs, addrs, n);
    memcpy(c->values, values, n * sizeof *values);
    c->accepted = !f->fail_next_commit;
    f->fail_next_commit = false;
    return c->accepted;
}

static inline void kt_fake_restart(void *ctx)
{
    kt_fake_t *f = ctx;
    f->restarts++;
}

static inline bool kt_fake_request(void *ctx, const km_request_t *req)
{
    kt_fake_t *f = ctx;
    assert_true(f->n_requests < KT_MAX_REQUESTS);
    f->requests[f->n_requests++] = *req;
    return !f->refuse_requests;
}

/* Value of `addr` in commit c, or fails the test if absent. */
static inline uint32_t kt_commit_value(const kt_commit_t *c, uint8_t addr)
{
    for (uint8_t i = 0; i < c->n; i++) {
        if (c->addrs[i] == addr) {
            return c->values[i];
        }
    }
    fail_msg("address 0x%02X not in the commit", addr);
    return 0;
}

static inline bool kt_commit_has(const kt_commit_t *c, uint8_t addr)
{
    for (uint8_t i = 0; i < c->n; i++) {
        if (c->addrs[i] == addr) {
            return true;
        }
    }
    return false;
}

/* ---- hex and frames ------------------------------------------------------- */

static inline int kt_nibble(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

/* Hex text ("F9 FF 01 ...", spaces optional) -> bytes; returns the count. */
static inline unsigned kt_hex(const char *hex, uint8_t *out, unsigned cap)
{
    unsigned n = 0;
    while (*hex) {
        if (*hex == ' ') {
            hex++;
            continue;
        }
        const int hi = kt_nibble(hex[0]);
        const int lo = hex[1] ? kt_nibble(hex[1]) : -1;
        assert_true(hi >= 0 && lo >= 0);
        assert_true(n < cap);
        out[n++] = (uint8_t)(hi * 16 + lo);
        hex += 2;
    }
    return n;
}

/* §2 checksum, written out here so the tests do not trust protocol/. */
static inline uint8_t kt_sum(const uint8_t *b, unsigned n)
{
    unsigned s = 0;
    for (unsigned i = 0; i < n; i++) {
        s += b[i];
    }
    return (uint8_t)(~s & 0xFFu);
}

/* A whole §2 command frame -> km_frame_t. Asserts header F9 FF, length byte =
 * bytes after it, and the checksum (so the worked frames are checked too). */
static inline void kt_frame_from_hex(const char *hex, km_frame_t *f)
{
    uint8_t b[KM_FRAME_MAX + 4];
    const unsigned n = kt_hex(hex, b, sizeof b);
    assert_true(n >= 6);
    assert_int_equal(b[0], 0xF9);
    assert_int_equal(b[1], 0xFF);
    assert_int_equal(b[3], n - 4u);
    assert_int_equal(b[n - 1], kt_sum(&b[2], n - 3u));
    memset(f, 0, sizeof *f);
    f->id = b[2];
    f->cmd = b[4];
    f->body_len = (uint8_t)(b[3] - 2u);
    memcpy(f->body, &b[5], f->body_len);
}

/* A command frame from its parts (what a parser would hand over). */
static inline void kt_frame(km_frame_t *f, uint8_t id, uint8_t cmd, const uint8_t *body, unsigned n)
{
    assert_true(n <= KM_BODY_MAX);
    memset(f, 0, sizeof *f);
    f->id = id;
    f->cmd = cmd;
    f->body_len = (uint8_t)n;
    if (n) {
        memcpy(f->body, body, n);
    }
}

/* A §2 frame F9 <hdr1> id len cmd body cs into out; returns its size. */
static inline unsigned kt_build_frame(uint8_t *out, uint8_t hdr1, uint8_t id, uint8_t cmd,
                                      const uint8_t *body, unsigned n)
{
    out[0] = 0xF9;
    out[1] = hdr1;
    out[2] = id;
    out[3] = (uint8_t)(n + 2u);
    out[4] = cmd;
    if (n) {
        memcpy(&out[5], body, n);
    }
    out[5 + n] = kt_sum(&out[2], n + 3u);
    return n + 6u;
}

/* Expected response frame F9 F5 id len cmd body cs, built from §2. */
static inline unsigned kt_response(uint8_t *out, uint8_t id, uint8_t cmd, const uint8_t *body, unsigned n)
{
    return kt_build_frame(out, 0xF5, id, cmd, body, n);
}

/* A command frame F9 FF id len cmd body cs, as a master sends it. */
static inline unsigned kt_command(uint8_t *out, uint8_t id, uint8_t cmd, const uint8_t *body, unsigned n)
{
    return kt_build_frame(out, 0xFF, id, cmd, body, n);
}

/* ---- fixture ---------------------------------------------------------------- */

typedef struct {
    km_servo_t s;
    kt_fake_t fake;
    km_servo_ops_t ops;
    km_reply_t reply;
    uint32_t persisted[KM_REG_COUNT];
} kt_fx_t;

/* Servo with the product's defaults and `id` as its stored ID (user data as
 * the store would hand it over at power-on). */
static inline void kt_init_seed(kt_fx_t *fx, const km_product_t *p, uint8_t id, uint32_t seed)
{
    memset(fx, 0, sizeof *fx);
    fx->ops.commit = kt_fake_commit;
    fx->ops.restart = kt_fake_restart;
    fx->ops.request = kt_fake_request;
    fx->ops.ctx = &fx->fake;
    unsigned k = 0;
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        if (!km_reg_table[i].persisted) {
            continue;
        }
        fx->persisted[k] = km_reg_table[i].addr == 0x0F ? id : km_reg_default((km_reg_index_t)i, p);
        k++;
    }
    km_servo_init(&fx->s, p, fx->persisted, seed, &fx->ops);
}

static inline void kt_init(kt_fx_t *fx, const km_product_t *p, uint8_t id)
{
    kt_init_seed(fx, p, id, 12345u);
}

static inline void kt_send_frame(kt_fx_t *fx, const km_frame_t *f)
{
    memset(&fx->reply, 0xA5, sizeof fx->reply);
    km_servo_handle(&fx->s, f, &fx->reply);
}

static inline void kt_send_hex(kt_fx_t *fx, const char *hex)
{
    km_frame_t f;
    kt_frame_from_hex(hex, &f);
    kt_send_frame(fx, &f);
}

static inline void kt_send(kt_fx_t *fx, uint8_t id, uint8_t cmd, const uint8_t *body, unsigned n)
{
    km_frame_t f;
    kt_frame(&f, id, cmd, body, n);
    kt_send_frame(fx, &f);
}

/* Write `n` value bytes to `addr` with command 0x03. */
static inline void kt_write(kt_fx_t *fx, uint8_t id, uint8_t addr, const uint8_t *val, unsigned n)
{
    uint8_t body[KM_BODY_MAX];
    body[0] = addr;
    if (n) {
        memcpy(&body[1], val, n);
    }
    kt_send(fx, id, 0x03, body, n + 1u);
}

static inline void kt_write_u8(kt_fx_t *fx, uint8_t id, uint8_t addr, uint8_t v)
{
    kt_write(fx, id, addr, &v, 1);
}

static inline void kt_write_u16(kt_fx_t *fx, uint8_t id, uint8_t addr, uint16_t v)
{
    const uint8_t b[2] = {(uint8_t)v, (uint8_t)(v >> 8)};
    kt_write(fx, id, addr, b, 2);
}

static inline void kt_read(kt_fx_t *fx, uint8_t id, uint8_t addr)
{
    kt_send(fx, id, 0x02, &addr, 1);
}

static inline void kt_ping(kt_fx_t *fx, uint8_t id)
{
    kt_send(fx, id, 0x01, NULL, 0);
}

/* Extension read 0x7F of `addr` (docs/protocol-decisions.md "Extension
 * command 0x7F"). */
static inline void kt_ext_read(kt_fx_t *fx, uint8_t id, uint8_t addr)
{
    kt_send(fx, id, 0x7F, &addr, 1);
}

/* Sets the stored value of persisted register `addr` in fx->persisted (what
 * the store hands over at the next kt_reinit). */
static inline void kt_persisted_set(kt_fx_t *fx, uint8_t addr, uint32_t v)
{
    unsigned k = 0;
    for (unsigned j = 0; j < KM_REG_COUNT; j++) {
        if (!km_reg_table[j].persisted)
            continue;
        if (km_reg_table[j].addr == addr) {
            fx->persisted[k] = v;
            return;
        }
        k++;
    }
    fail_msg("0x%02X is not persisted", addr);
}

/* Re-initialises the servo from fx->persisted (a restart or power-on); the
 * fake's records are kept. */
static inline void kt_reinit(kt_fx_t *fx, const km_product_t *p)
{
    km_servo_init(&fx->s, p, fx->persisted, 12345u, &fx->ops);
}

/* The last reply equals these hex bytes. */
static inline void kt_reply_is_hex(const kt_fx_t *fx, const char *hex)
{
    uint8_t want[KM_FRAME_MAX];
    const unsigned n = kt_hex(hex, want, sizeof want);
    assert_int_equal(fx->reply.len, n);
    assert_memory_equal(fx->reply.bytes, want, n);
}

/* The last reply is the short response `F9 F5 id 02 status cs`. */
static inline void kt_reply_is_status(const kt_fx_t *fx, uint8_t id, uint8_t status)
{
    uint8_t want[6];
    want[0] = 0xF9;
    want[1] = 0xF5;
    want[2] = id;
    want[3] = 0x02;
    want[4] = status;
    want[5] = kt_sum(&want[2], 3);
    assert_int_equal(fx->reply.len, 6);
    assert_memory_equal(fx->reply.bytes, want, 6);
}

/* The last reply is a read answer for `addr` with these value bytes. */
static inline void kt_reply_is_read(const kt_fx_t *fx, uint8_t id, uint8_t addr, const uint8_t *val,
                                    unsigned n)
{
    uint8_t body[32];
    uint8_t want[40];
    assert_true(n + 1u <= sizeof body);
    body[0] = addr;
    memcpy(&body[1], val, n);
    const unsigned len = kt_response(want, id, 0x02, body, n + 1u);
    assert_int_equal(fx->reply.len, len);
    assert_memory_equal(fx->reply.bytes, want, len);
}

static inline void kt_no_reply(const kt_fx_t *fx)
{
    assert_int_equal(fx->reply.len, 0);
}

/* Pings `id` and checks the short response carries `status` (a ping reports
 * and clears the unreported bits 5/6). */
static inline void kt_ping_is(kt_fx_t *fx, uint8_t id, uint8_t status)
{
    kt_ping(fx, id);
    kt_reply_is_status(fx, id, status);
}

/* The protocol's own commands answer at `id`: a ping (status 0) and a read
 * of 0x0F, the ID (docs/protocol.md §3, §5.1). */
static inline void kt_spec_commands_answer(kt_fx_t *fx, uint8_t id)
{
    kt_ping_is(fx, id, 0);
    const uint8_t addr = 0x0F;
    kt_send(fx, id, 0x02, &addr, 1u);
    kt_reply_is_read(fx, id, addr, &id, 1u);
}

/* Value bytes of the last read answer (asserts it is one for `addr`). */
static inline unsigned kt_read_value(const kt_fx_t *fx, uint8_t addr, uint8_t *out)
{
    assert_true(fx->reply.len >= 7);
    assert_int_equal(fx->reply.bytes[4], 0x02);
    assert_int_equal(fx->reply.bytes[5], addr);
    const unsigned n = fx->reply.len - 7u;
    memcpy(out, &fx->reply.bytes[6], n);
    return n;
}

/* Little-endian value of the last read answer. */
static inline uint32_t kt_read_le(const kt_fx_t *fx, uint8_t addr)
{
    uint8_t v[32];
    const unsigned n = kt_read_value(fx, addr, v);
    uint32_t x = 0;
    for (unsigned i = 0; i < n && i < 4; i++) {
        x |= (uint32_t)v[i] << (8u * i);
    }
    return x;
}

/* ---- snapshot: what a rejected input must leave alone ------------------------ */

typedef struct {
    uint32_t value[KM_REG_COUNT];
    uint32_t active_baud;
    uint8_t hw_latched;
    bool sync_full;
    uint8_t sync_addr, sync_len;
    uint8_t sync_data[8];
    uint8_t unreported; /* bits 5/6 no status answer has carried yet */
    bool restarting;
    uint8_t userdata_source, reset_cause;
    unsigned n_commits, restarts, n_requests;
} kt_snap_t;

static inline void kt_snap(const kt_fx_t *fx, kt_snap_t *sn)
{
    memset(sn, 0, sizeof *sn);
    memcpy(sn->value, fx->s.reg.value, sizeof sn->value);
    sn->active_baud = fx->s.active_baud;
    sn->hw_latched = fx->s.reg.hw_latched;
    sn->sync_full = fx->s.sync.full;
    sn->sync_addr = fx->s.sync.addr;
    sn->sync_len = fx->s.sync.len;
    memcpy(sn->sync_data, fx->s.sync.data, sizeof sn->sync_data);
    sn->unreported = fx->s.reg.unreported;
    sn->restarting = fx->s.restarting;
    sn->userdata_source = fx->s.userdata_source;
    sn->reset_cause = fx->s.reset_cause;
    sn->n_commits = fx->fake.n_commits;
    sn->restarts = fx->fake.restarts;
    sn->n_requests = fx->fake.n_requests;
}

static inline void kt_assert_unchanged(const kt_fx_t *fx, const kt_snap_t *before)
{
    kt_snap_t now;
    kt_snap(fx, &now);
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        if (now.value[i] != before->value[i]) {
            fail_msg("register 0x%02X changed: 0x%X -> 0x%X", km_reg_table[i].addr,
                     (unsigned)before->value[i], (unsigned)now.value[i]);
        }
    }
    assert_int_equal(now.active_baud, before->active_baud);
    assert_int_equal(now.hw_latched, before->hw_latched);
    assert_int_equal(now.sync_full, before->sync_full);
    if (before->sync_full) {
        assert_int_equal(now.sync_addr, before->sync_addr);
        assert_int_equal(now.sync_len, before->sync_len);
        assert_memory_equal(now.sync_data, before->sync_data, sizeof now.sync_data);
    }
    /* "Status bits 5 and 6": an input whose outcome waits for the next ping
     * changes the unreported bits; such a test adds them to the snapshot
     * (sn.unreported |= ...) before comparing. */
    if (now.unreported != before->unreported) {
        fail_msg("unreported bits changed: 0x%02X -> 0x%02X", before->unreported, now.unreported);
    }
    assert_int_equal(now.restarting, before->restarting);
    assert_int_equal(now.userdata_source, before->userdata_source);
    assert_int_equal(now.reset_cause, before->reset_cause);
    assert_int_equal(now.n_commits, before->n_commits);
    assert_int_equal(now.restarts, before->restarts);
    assert_int_equal(now.n_requests, before->n_requests);
}

/* ---- §3 super-ID slot rule, as docs/protocol.md / docs state it ----------------- */

/* ceil(((answer_bytes + 2) x 10 bits) x 1e6 / baud) us */
static inline uint32_t kt_slot_us(unsigned answer_bytes, uint32_t baud)
{
    const uint64_t bits = (uint64_t)(answer_bytes + 2u) * 10u;
    return (uint32_t)((bits * 1000000u + baud - 1u) / baud);
}

/* xorshift32 (13, 17, 5), the generator the 0x01 random byte comes from. */
static inline uint32_t kt_xorshift32(uint32_t x)
{
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return x;
}

#endif
