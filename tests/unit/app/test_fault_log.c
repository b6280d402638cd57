/* SPDX-License-Identifier: Apache-2.0 */
/* firmware/app/km_fault_log.c: the ring of the last 16 protection and
 * self-test events, kept across a reset (RAM that the reset leaves), never
 * across damage: power-up garbage and a log torn mid-update start empty;
 * written from the events control reports with its live values. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_fault_log.h"

static km_fault_entry_t entry(uint32_t t, uint8_t kind, uint8_t bits)
{
    km_fault_entry_t e;
    memset(&e, 0, sizeof e);
    e.t_ms = t;
    e.kind = kind;
    e.bits = bits;
    e.voltage_mv = 5400;
    e.current_ma = -1234;
    e.temp_c10 = 612;
    e.position = -3601;
    return e;
}

/* Power-up RAM (garbage or zero) is not a log: it starts empty. */
static void test_boot_on_garbage_starts_empty(void **state)
{
    (void)state;
    km_fault_log_t log;
    memset(&log, 0xA5, sizeof log);
    assert_false(km_fault_log_boot(&log));
    assert_int_equal(log.held, 0);
    assert_int_equal(log.total, 0);
    memset(&log, 0, sizeof log);
    assert_false(km_fault_log_boot(&log));
    km_fault_entry_t e;
    assert_false(km_fault_log_get(&log, 0, &e));
}

/* Newest first; 16 held; the 17th drops the oldest; total counts all. */
static void test_ring_newest_first(void **state)
{
    (void)state;
    km_fault_log_t log;
    memset(&log, 0, sizeof log);
    (void)km_fault_log_boot(&log);
    for (uint32_t i = 1; i <= 20; i++) {
        const km_fault_entry_t e = entry(i * 10u, KM_FAULT_EV_TRIP, (uint8_t)(i & 0x0Fu));
        km_fault_log_add(&log, &e);
    }
    assert_int_equal(log.held, KM_FAULT_LOG_LEN);
    assert_int_equal(log.total, 20);
    km_fault_entry_t e;
    assert_true(km_fault_log_get(&log, 0, &e));
    assert_int_equal(e.t_ms, 200);
    assert_true(km_fault_log_get(&log, 15, &e));
    assert_int_equal(e.t_ms, 50);
    assert_false(km_fault_log_get(&log, 16, &e));
}

/* A reset keeps a log that checks: entries one boot older, counted as kept;
 * new entries are this boot's; overwriting a kept one lowers the count. */
static void test_kept_across_reset(void **state)
{
    (void)state;
    km_fault_log_t log;
    memset(&log, 0, sizeof log);
    (void)km_fault_log_boot(&log);
    for (uint32_t i = 0; i < 3; i++) {
        const km_fault_entry_t e = entry(i, KM_FAULT_EV_HW, 0x20);
        km_fault_log_add(&log, &e);
    }
    assert_true(km_fault_log_boot(&log)); /* the reset */
    assert_int_equal(log.kept, 3);
    km_fault_entry_t e;
    assert_true(km_fault_log_get(&log, 0, &e));
    assert_int_equal(e.boots_ago, 1);
    assert_true(km_fault_log_boot(&log)); /* and another */
    assert_true(km_fault_log_get(&log, 2, &e));
    assert_int_equal(e.boots_ago, 2);
    const km_fault_entry_t n = entry(99, KM_FAULT_EV_CLEAR, 0x01);
    km_fault_log_add(&log, &n);
    assert_true(km_fault_log_get(&log, 0, &e));
    assert_int_equal(e.boots_ago, 0);
    assert_int_equal(e.t_ms, 99);
    for (int i = 0; i < 14; i++) {
        km_fault_log_add(&log, &n);
    }
    assert_int_equal(log.held, 16);
    assert_int_equal(log.kept, 1); /* 3 kept + 15 new in 16 slots: 2 kept dropped */
}

/* A log torn by a reset in the middle of an update starts empty. */
static void test_torn_update_is_not_kept(void **state)
{
    (void)state;
    km_fault_log_t log;
    memset(&log, 0, sizeof log);
    (void)km_fault_log_boot(&log);
    const km_fault_entry_t e = entry(5, KM_FAULT_EV_TRIP, 0x04);
    km_fault_log_add(&log, &e);
    log.check = ~log.check; /* as km_fault_log_add leaves it mid-way */
    log.entries[1].t_ms = 77;
    assert_false(km_fault_log_boot(&log));
    assert_int_equal(log.held, 0);
    memset(&log, 0, sizeof log);
    (void)km_fault_log_boot(&log);
    km_fault_log_add(&log, &e);
    log.entries[0].bits ^= 1u; /* one flipped bit */
    assert_false(km_fault_log_boot(&log));
}

/* The wire forms of 0x7F (docs/protocol-decisions.md "Fault log"). */
static void test_wire_forms(void **state)
{
    (void)state;
    km_fault_log_t log;
    memset(&log, 0, sizeof log);
    (void)km_fault_log_boot(&log);
    const km_fault_entry_t e = entry(0x01020304u, KM_FAULT_EV_TRIP, 0x09);
    km_fault_log_add(&log, &e);
    uint8_t b[KM_FAULT_ENTRY_SIZE];
    assert_int_equal(km_fault_log_summary(&log, b), KM_FAULT_SUMMARY_SIZE);
    const uint8_t sum[] = {1, 0, 0, 0, 1, 0, 16};
    assert_memory_equal(b, sum, sizeof sum);
    km_fault_entry_t got;
    assert_true(km_fault_log_get(&log, 0, &got));
    assert_int_equal(km_fault_log_entry_bytes(&got, b), KM_FAULT_ENTRY_SIZE);
    const uint8_t want[] = {0x04, 0x03, 0x02, 0x01, 1,    0x09, 0,    0,    0x18,
                            0x15, 0x2E, 0xFB, 0x64, 0x02, 0xEF, 0xF1, 0xFF, 0xFF};
    assert_memory_equal(b, want, sizeof want);
}

/* One control tick's events become entries in a fixed order (trips,
 * clears, releases, hardware faults), each with that tick's live state
 * (voltage and current clamped to their 16-bit fields, temperature in
 * 0.1 degC); a tick without events adds nothing. */
static void test_record_from_control_events(void **state)
{
    (void)state;
    km_fault_log_t log;
    memset(&log, 0, sizeof log);
    (void)km_fault_log_boot(&log);
    km_live_t live;
    memset(&live, 0, sizeof live);
    live.time_ms = 1234;
    live.position = -40000;
    live.voltage = 70000;
    live.current = -40000;
    live.temperature = 61;
    km_fault_log_record(&log, &live);
    assert_int_equal(log.total, 0);
    live.events.tripped = 0x04;
    live.events.cleared = 0x01;
    live.events.released = 0x08;
    live.events.hw_found = 0x20;
    km_fault_log_record(&log, &live);
    assert_int_equal(log.total, 4);
    static const struct {
        uint8_t kind, bits;
    } want[4] = {{KM_FAULT_EV_HW, 0x20},
                 {KM_FAULT_EV_RELEASE, 0x08},
                 {KM_FAULT_EV_CLEAR, 0x01},
                 {KM_FAULT_EV_TRIP, 0x04}};
    for (uint8_t n = 0; n < 4; n++) { /* newest first */
        km_fault_entry_t e;
        assert_true(km_fault_log_get(&log, n, &e));
        assert_int_equal(e.kind, want[n].kind);
        assert_int_equal(e.bits, want[n].bits);
        assert_int_equal(e.t_ms, 1234);
        assert_int_equal(e.position, -40000);
        assert_int_equal(e.voltage_mv, 65535);
        assert_int_equal(e.current_ma, -32768);
        assert_int_equal(e.temp_c10, 610);
    }
    live.events.tripped = 0;
    live.events.cleared = 0;
    live.events.released = 0x02;
    live.events.hw_found = 0;
    km_fault_log_record(&log, &live);
    assert_int_equal(log.total, 5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_boot_on_garbage_starts_empty),
        cmocka_unit_test(test_ring_newest_first),
        cmocka_unit_test(test_kept_across_reset),
        cmocka_unit_test(test_torn_update_is_not_kept),
        cmocka_unit_test(test_wire_forms),
        cmocka_unit_test(test_record_from_control_events),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
