/* SPDX-License-Identifier: Apache-2.0 */
/* docs/protocol.md §5 register by register, driven from km_reg_table: every
 * default reads back, every stored RW register takes its range edges and
 * refuses the values just outside with nothing changed, cross-field rules.
 * Expected defaults and ranges are written here from §5 and the product
 * config, not taken from km_registers.def. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_hooks.h"
#include "km_test_support.h"

#define ID 9
static kt_fx_t fx;

/* §5 defaults ("—" = the product's value), as packed wire bytes. */
static bool spec_default(uint8_t addr, const km_product_t *p, uint32_t *out)
{
    switch (addr) {
    case 0x0F:
        *out = ID;
        return true; /* the fixture stores its ID; 0 by default (§5.1) */
    case 0x10:
        *out = 1152;
        return true;
    case 0x11:
        *out = 0x02;
        return true;
    case 0x12:
        *out = 200;
        return true;
    case 0x13:
        *out = 1000;
        return true;
    case 0x14:
        *out = p->max_current_ma;
        return true;
    case 0x15:
        *out = p->max_speed_dps;
        return true;
    case 0x16:
        *out = (uint16_t)p->zero_offset1;
        return true;
    case 0x17:
        *out = 0;
        return true;
    case 0x19:
        *out = (uint16_t)p->angle_min;
        return true;
    case 0x1A:
        *out = (uint16_t)p->angle_max;
        return true;
    case 0x32:
        *out = 0x0F;
        return true;
    case 0x33:
        *out = 0x00;
        return true;
    case 0x34:
        *out = 0x54;
        return true;
    case 0x35:
        *out = 0;
        return true;
    case 0x36:
        *out = 0;
        return true;
    case 0x3C:
        *out = (uint32_t)p->voltage_high_v | ((uint32_t)p->voltage_low_v << 8);
        return true;
    case 0x3D:
        *out = 60u | (5u << 8);
        return true;
    case 0x3E:
        *out = (uint32_t)p->current_threshold_ma | (20u << 16);
        return true;
    case 0x3F:
        *out = 600u | (20u << 16);
        return true;
    case 0x5A:
        *out = 0;
        return true;
    case 0x5B:
        *out = 1000;
        return true;
    case 0x5C:
        *out = p->max_current_ma;
        return true;
    case 0x5D:
        *out = p->max_speed_dps;
        return true;
    case 0x64:
        *out = 3;
        return true;
    default:
        return false;
    }
}

/* §5 ranges of the single-value RW registers. */
typedef struct {
    uint8_t size;
    bool is_signed;
    int32_t lo, hi;
} range_t;

static bool spec_range(uint8_t addr, const km_product_t *p, range_t *r)
{
    switch (addr) {
    case 0x0F:
        *r = (range_t){1, false, 0, 250};
        return true;
    case 0x10:
        *r = (range_t){2, false, p->baud_min_100, p->baud_max_100};
        return true;
    case 0x12:
        *r = (range_t){2, false, 0, 65535};
        return true;
    case 0x13:
        *r = (range_t){2, false, 0, 1000};
        return true;
    case 0x14:
        *r = (range_t){2, false, 0, p->current_max_ma};
        return true;
    case 0x15:
        *r = (range_t){2, false, 0, p->speed_max_dps};
        return true;
    case 0x17:
        *r = (range_t){2, true, -p->zero_offset2_max, p->zero_offset2_max};
        return true;
    case 0x19:
    case 0x1A:
        *r = (range_t){2, true, p->travel_min, p->travel_max};
        return true;
    case 0x5A:
        *r = (range_t){1, false, 0, 2};
        return true;
    case 0x5B:
        *r = (range_t){2, false, 0, 1000};
        return true;
    case 0x5C:
        *r = (range_t){2, false, 0, p->current_max_ma};
        return true;
    case 0x5D:
        *r = (range_t){2, false, 0, p->speed_max_dps};
        return true;
    case 0x64:
        *r = (range_t){1, false, 0, 3};
        return true;
    default:
        return false;
    }
}

/* "Reserved bits": the bit-field registers and the mask of their defined
 * bits (§5.1 0x11 bits 0..3, §5.2 0x32/0x33/0x36 bits 0..3). */
static bool spec_bits(uint8_t addr, uint8_t *mask)
{
    switch (addr) {
    case 0x11:
    case 0x32:
    case 0x33:
    case 0x36:
        *mask = 0x0F;
        return true;
    default:
        return false;
    }
}

static const km_product_t *product(unsigned i)
{
    return i == 0 ? kt_product_pot() : kt_product_enc();
}

/* Every readable register with a stored value reads back its §5 default. */
static void test_s5_defaults_read_back(void **state)
{
    (void)state;
    for (unsigned pi = 0; pi < 2; pi++) {
        const km_product_t *p = product(pi);
        unsigned checked = 0;
        for (unsigned i = 0; i < KM_REG_COUNT; i++) {
            const uint8_t a = km_reg_table[i].addr;
            uint32_t want;
            if (!(km_reg_table[i].access & KM_R) || !spec_default(a, p, &want)) {
                continue;
            }
            kt_init(&fx, p, ID);
            kt_read(&fx, ID, a);
            const uint32_t got = kt_read_le(&fx, a);
            if (got != want) {
                fail_msg("0x%02X default 0x%X, want 0x%X", a, (unsigned)got, (unsigned)want);
            }
            checked++;
        }
        assert_int_equal(checked, 25);
    }
}

/* A stored RW register without a §5 default or range here means the table
 * and this test disagree. */
static void test_s5_every_rw_register_covered(void **state)
{
    (void)state;
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        const km_reg_t *r = &km_reg_table[i];
        uint32_t d;
        range_t rg;
        if (r->access != KM_RW || r->addr == 0x46) {
            continue; /* 0x46 R(W): a write zeroes (test_dispatch_commands) */
        }
        if (!spec_default(r->addr, kt_product_pot(), &d)) {
            fail_msg("no spec default for RW 0x%02X", r->addr);
        }
        const bool multi = r->addr == 0x34 || (r->addr >= 0x3C && r->addr <= 0x3F);
        uint8_t mask;
        if (!multi && !spec_range(r->addr, kt_product_pot(), &rg) && !spec_bits(r->addr, &mask)) {
            fail_msg("no spec range for RW 0x%02X", r->addr);
        }
    }
}

static void put(uint8_t *b, int32_t v, uint8_t size)
{
    for (uint8_t i = 0; i < size; i++) {
        b[i] = (uint8_t)((uint32_t)v >> (8u * i));
    }
}

static int32_t as_value(uint32_t raw, const range_t *r)
{
    if (!r->is_signed)
        return (int32_t)raw;
    return r->size == 1 ? (int8_t)raw : (int16_t)raw;
}

/* "Limits that contradict each other": a range edge of one limit is tested
 * with its counterpart out of the way (0x14/0x15 at their top for 0x5C/0x5D,
 * the other angle limit 0 = no limit); the cross rules have their own tests
 * in test_dispatch_commands.c. */
static void init_for(const km_product_t *p, uint8_t a)
{
    kt_init(&fx, p, ID);
    switch (a) {
    case 0x19:
        kt_persisted_set(&fx, 0x1A, 0);
        break;
    case 0x1A:
        kt_persisted_set(&fx, 0x19, 0);
        break;
    case 0x5C:
        kt_persisted_set(&fx, 0x14, p->current_max_ma);
        break;
    case 0x5D:
        kt_persisted_set(&fx, 0x15, p->speed_max_dps);
        break;
    default:
        return;
    }
    kt_reinit(&fx, p);
}

/* RW write and read-back at both range edges; the values just outside (if
 * the wire size can carry them) are refused with bit 6 and nothing changes. */
static void test_s5_rw_range_edges(void **state)
{
    (void)state;
    for (unsigned pi = 0; pi < 2; pi++) {
        const km_product_t *p = product(pi);
        for (unsigned i = 0; i < KM_REG_COUNT; i++) {
            const uint8_t a = km_reg_table[i].addr;
            range_t r;
            if (km_reg_table[i].access != KM_RW || !spec_range(a, p, &r)) {
                continue;
            }
            const int32_t wire_lo = r.is_signed ? -(1 << (8 * r.size - 1)) : 0;
            const int32_t wire_hi = r.is_signed ? (1 << (8 * r.size - 1)) - 1 : (1 << (8 * r.size)) - 1;
            const int32_t edges[2] = {r.lo, r.hi};
            for (unsigned e = 0; e < 2; e++) {
                init_for(p, a);
                uint8_t b[2];
                put(b, edges[e], r.size);
                kt_write(&fx, ID, a, b, r.size);
                if (km_servo_status(&fx.s) != 0) {
                    fail_msg("0x%02X = %d refused", a, (int)edges[e]);
                }
                const uint8_t id = a == 0x0F ? (uint8_t)edges[e] : ID;
                kt_read(&fx, id, a);
                assert_int_equal(as_value(kt_read_le(&fx, a), &r), edges[e]);
            }
            const int32_t outside[2] = {r.lo - 1, r.hi + 1};
            for (unsigned e = 0; e < 2; e++) {
                if (outside[e] < wire_lo || outside[e] > wire_hi) {
                    continue;
                }
                init_for(p, a);
                kt_snap_t sn;
                kt_snap(&fx, &sn);
                uint8_t b[2];
                put(b, outside[e], r.size);
                kt_write(&fx, ID, a, b, r.size);
                if (km_servo_status(&fx.s) != KM_ST_FAILED) {
                    fail_msg("0x%02X = %d accepted", a, (int)outside[e]);
                }
                sn.unreported |= KM_ST_FAILED; /* level 0: the next ping reports it */
                kt_assert_unchanged(&fx, &sn);
            }
        }
    }
}

/* Persisted registers are committed with the packed value; live-only ones
 * (0x5A..0x5D, 0x64) are not committed. */
static void test_s5_persisted_writes_committed(void **state)
{
    (void)state;
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        const uint8_t a = km_reg_table[i].addr;
        range_t r;
        if (km_reg_table[i].access != KM_RW || !spec_range(a, kt_product_pot(), &r)) {
            continue;
        }
        init_for(kt_product_pot(), a);
        uint8_t b[2];
        put(b, r.hi, r.size);
        kt_write(&fx, ID, a, b, r.size);
        assert_int_equal(km_servo_status(&fx.s), 0);
        const bool p = a < 0x5A; /* §5: P column */
        assert_int_equal(fx.fake.n_commits, p ? 1u : 0u);
        if (p) {
            assert_int_equal(fx.fake.commits[0].n, 1);
            assert_int_equal(fx.fake.commits[0].addrs[0], a);
            assert_int_equal(fx.fake.commits[0].values[0], (uint32_t)r.hi & (r.size == 1 ? 0xFFu : 0xFFFFu));
        }
    }
}

static void write_expect(uint8_t a, const uint8_t *b, unsigned n, bool ok)
{
    kt_init(&fx, kt_product_pot(), ID);
    kt_snap_t sn;
    kt_snap(&fx, &sn);
    kt_write(&fx, ID, a, b, n);
    if (ok) {
        if (km_servo_status(&fx.s) != 0) {
            fail_msg("0x%02X refused %02X %02X %02X", a, b[0], n > 1 ? b[1] : 0, n > 2 ? b[2] : 0);
        }
        kt_read(&fx, ID, a);
        uint8_t got[4];
        assert_int_equal(kt_read_value(&fx, a, got), n);
        assert_memory_equal(got, b, n);
    } else {
        if (km_servo_status(&fx.s) != KM_ST_FAILED) {
            fail_msg("0x%02X accepted %02X %02X %02X", a, b[0], n > 1 ? b[1] : 0, n > 2 ? b[2] : 0);
        }
        sn.unreported |= KM_ST_FAILED; /* level 0: the next ping reports it */
        kt_assert_unchanged(&fx, &sn);
    }
}

/* §5.2 0x34: stall and current fields take 00..11, temperature and voltage
 * only 00/01. */
static void test_s5_2_0x34_field_rules(void **state)
{
    (void)state;
    for (unsigned v = 0; v < 256; v++) {
        const bool temp_ok = ((v >> 4) & 3u) <= 1u;
        const bool volt_ok = (v & 3u) <= 1u;
        const uint8_t b = (uint8_t)v;
        write_expect(0x34, &b, 1, temp_ok && volt_ok);
    }
}

/* §5.2 0x3C: both fields within the product's voltage bound, high > low. */
static void test_s5_2_0x3C_voltage_thresholds(void **state)
{
    (void)state;
    const uint8_t vmax = kt_product_pot()->voltage_max_v;
    const struct {
        uint8_t h, l;
        bool ok;
    } c[] = {
        {vmax, (uint8_t)(vmax - 1), true}, {1, 0, true},  {12, 6, true}, {10, 10, false}, {5, 10, false},
        {(uint8_t)(vmax + 1), 5, false},   {0, 0, false},
    };
    for (unsigned i = 0; i < sizeof c / sizeof c[0]; i++) {
        const uint8_t b[2] = {c[i].h, c[i].l};
        write_expect(0x3C, b, 2, c[i].ok);
    }
}

/* §5.2 0x3D: trip, hysteresis; the hysteresis below the trip temperature. */
static void test_s5_2_0x3D_temperature_thresholds(void **state)
{
    (void)state;
    const struct {
        uint8_t t, h;
        bool ok;
    } c[] = {
        {60, 59, true}, {255, 254, true}, {1, 0, true}, {60, 60, false}, {0, 0, false}, {50, 200, false},
    };
    for (unsigned i = 0; i < sizeof c / sizeof c[0]; i++) {
        const uint8_t b[2] = {c[i].t, c[i].h};
        write_expect(0x3D, b, 2, c[i].ok);
    }
}

/* §5.2 0x3E/0x3F: threshold within range, detection time at least 1 (100 ms). */
static void test_s5_2_0x3E_0x3F_thresholds_and_detection_time(void **state)
{
    (void)state;
    const uint16_t cmax = kt_product_pot()->current_max_ma;
    const struct {
        uint8_t a;
        uint16_t v;
        uint8_t t;
        bool ok;
    } c[] = {
        {0x3E, cmax, 1, true},  {0x3E, 0, 255, true},  {0x3E, (uint16_t)(cmax + 1), 20, false},
        {0x3E, 1000, 0, false}, {0x3F, 1000, 1, true}, {0x3F, 0, 20, true},
        {0x3F, 1001, 1, false}, {0x3F, 600, 0, false},
    };
    for (unsigned i = 0; i < sizeof c / sizeof c[0]; i++) {
        const uint8_t b[3] = {(uint8_t)c[i].v, (uint8_t)(c[i].v >> 8), c[i].t};
        write_expect(c[i].a, b, 3, c[i].ok);
    }
}

/* "Reserved bits": 0x11, 0x32 and 0x33 define bits 0..3; a write with any
 * of bits 4..7 set is accepted, the defined bits apply, the reserved ones
 * are stored (and committed) as 0 and read back as 0. */
static void test_s5_reserved_bits_accepted_stored_zero(void **state)
{
    (void)state;
    static const uint8_t addrs[] = {0x11, 0x32, 0x33};
    for (unsigned i = 0; i < sizeof addrs; i++) {
        const uint8_t a = addrs[i];
        for (unsigned v = 0; v < 256; v++) {
            kt_init(&fx, kt_product_pot(), ID);
            kt_write_u8(&fx, ID, a, (uint8_t)v);
            const uint8_t want = (uint8_t)(v & 0x0Fu);
            /* 0x11 bit 3 = response level 1 takes effect for this write's answer */
            if (a == 0x11 && (want & 0x08u)) {
                kt_reply_is_status(&fx, ID, 0);
            } else {
                kt_no_reply(&fx);
            }
            if (km_servo_status(&fx.s) != 0) {
                fail_msg("0x%02X = 0x%02X refused", a, v);
            }
            assert_int_equal(fx.fake.n_commits, 1);
            assert_int_equal(fx.fake.commits[0].n, 1);
            assert_int_equal(fx.fake.commits[0].addrs[0], a);
            assert_int_equal(fx.fake.commits[0].values[0], want);
            kt_read(&fx, ID, a);
            kt_reply_is_read(&fx, ID, a, &want, 1);
        }
    }
}

/* "Reserved bits" and 0x36: a write with bits 4..7 set is accepted as the
 * clear request of its bits 0..3 (bits 4..7 dropped); nothing is stored or
 * committed, and a read returns the live protections. */
static void test_s5_2_0x36_reserved_bits_masked_request(void **state)
{
    (void)state;
    for (unsigned v = 0; v < 256; v++) {
        kt_init(&fx, kt_product_pot(), ID);
        km_live_t live = {0};
        live.protections = 0x06;
        km_servo_set_live(&fx.s, &live);
        kt_write_u8(&fx, ID, 0x36, (uint8_t)v);
        if (km_servo_status(&fx.s) != 0x06) { /* bits 1, 2 live; no 5/6 */
            fail_msg("0x36 = 0x%02X: status 0x%02X", v, km_servo_status(&fx.s));
        }
        assert_int_equal(fx.fake.n_requests, 1);
        assert_int_equal(fx.fake.requests[0].kind, KM_REQ_PROTECTION_CLEAR);
        assert_int_equal(fx.fake.requests[0].u.clear, v & 0x0Fu);
        assert_int_equal(fx.fake.n_commits, 0);
        kt_read(&fx, ID, 0x36);
        const uint8_t p = 0x06;
        kt_reply_is_read(&fx, ID, 0x36, &p, 1);
    }
}

/* User data handed over at power-on passes the same checks as a write: a
 * stored value out of range (a baud of 0, a torque of 5000, an ID of 251)
 * falls back to its default instead of running with it (a baud of 0 made the
 * super-ID slot divide by zero). */
static void test_s5_persisted_values_checked_at_init(void **state)
{
    (void)state;
    static const struct {
        uint8_t addr;
        uint32_t bad;
        uint32_t want;
    } c[] = {
        {0x10, 0, 1152},
        {0x10, 10001, 1152},
        {0x13, 5000, 1000},
        {0x0F, 251, 0},
        {0x11, 0xF2, 0x02},
        {0x3D, 60u | (60u << 8), 60u | (5u << 8)},
        {0x13, 0x10000u | 500u, 1000}, /* garbage above the wire bytes */
    };
    for (unsigned i = 0; i < sizeof c / sizeof c[0]; i++) {
        kt_init(&fx, kt_product_pot(), ID);
        unsigned k = 0;
        for (unsigned j = 0; j < KM_REG_COUNT; j++) {
            if (!km_reg_table[j].persisted)
                continue;
            if (km_reg_table[j].addr == c[i].addr)
                fx.persisted[k] = c[i].bad;
            k++;
        }
        km_servo_init(&fx.s, kt_product_pot(), fx.persisted, 1, &fx.ops);
        const int r = km_reg_find(c[i].addr);
        assert_int_equal(km_servo_reg(&fx.s, (km_reg_index_t)r), c[i].want);
        kt_ping(&fx, KM_ID_SUPER);
        assert_int_equal(fx.reply.len, 6);
    }
    assert_int_equal(km_servo_active_baud(&fx.s), 115200);
    assert_int_equal(km_servo_reg(&fx.s, KM_REG_TORQUE_LIMIT), 1000);
}

/* km_registers.def's behaviour columns agree with its access column: a
 * register has a read hook exactly when it is readable and a write hook
 * exactly when it is writable (`none` otherwise); 0x83 takes exactly the
 * §3 list (0x64 one byte, 0x65/0x66 two or four, 0x68/0x6E/0x6F two). */
static void test_s5_behaviour_columns_match_access(void **state)
{
    (void)state;
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        const km_reg_t *r = &km_reg_table[i];
        if (((r->access & KM_R) != 0) != (km_reg_read((int)i) != km_rd_none)) {
            fail_msg("0x%02X %s: read hook and access disagree", r->addr, km_reg_names[i]);
        }
        if (((r->access & KM_W) != 0) != (km_reg_write((int)i) != km_wr_none)) {
            fail_msg("0x%02X %s: write hook and access disagree", r->addr, km_reg_names[i]);
        }
        uint8_t want = 0;
        switch (r->addr) {
        case 0x64:
            want = KM_K(1);
            break;
        case 0x65:
        case 0x66:
            want = KM_K(2) | KM_K(4);
            break;
        case 0x68:
        case 0x6E:
        case 0x6F:
            want = KM_K(2);
            break;
        default:
            break;
        }
        assert_int_equal(r->multi, want);
        assert_true(r->multi == 0u || (r->access & KM_W));
    }
    /* the address look-up finds every row, and nothing else */
    for (unsigned a = 0; a < 256u; a++) {
        int want = -1;
        for (unsigned i = 0; i < KM_REG_COUNT; i++) {
            if (km_reg_table[i].addr == a) {
                want = (int)i;
            }
        }
        assert_int_equal(km_reg_find((uint8_t)a), want);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s5_defaults_read_back),
        cmocka_unit_test(test_s5_behaviour_columns_match_access),
        cmocka_unit_test(test_s5_every_rw_register_covered),
        cmocka_unit_test(test_s5_rw_range_edges),
        cmocka_unit_test(test_s5_persisted_writes_committed),
        cmocka_unit_test(test_s5_reserved_bits_accepted_stored_zero),
        cmocka_unit_test(test_s5_2_0x36_reserved_bits_masked_request),
        cmocka_unit_test(test_s5_persisted_values_checked_at_init),
        cmocka_unit_test(test_s5_2_0x34_field_rules),
        cmocka_unit_test(test_s5_2_0x3C_voltage_thresholds),
        cmocka_unit_test(test_s5_2_0x3D_temperature_thresholds),
        cmocka_unit_test(test_s5_2_0x3E_0x3F_thresholds_and_detection_time),
    };
    return cmocka_run_group_tests_name("registers", tests, NULL, NULL);
}
