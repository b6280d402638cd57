/* SPDX-License-Identifier: Apache-2.0 */
/* Issue 19: a register can be added by touching only the .def files and
 * one hook (docs/architecture.md "Adding a register"). This test is built
 * against a copy of protocol/ to which tests/extend/add_register.cmake
 * added one register, 0x71 DEMO_ACCUMULATE, by appending a row to each
 * .def file (rows.def, rows_doc.def) and nothing else; its one hook is
 * km_hook_demo.c. Every path a register takes through the dispatcher must
 * then know it without another edit: read 0x02 (and at the super ID),
 * write 0x03 through its hook (and the range check it asks for), the
 * 0x04/0x84 sync write, the 0x83 multi-ID write (its `multi` column: a
 * hard-coded list would refuse it), the 0x82 multi-ID read, the name and
 * the generated tables. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "km_hooks.h"
#include "km_test_support.h"

#define ID 3
#define DEMO 0x71

static kt_fx_t fx;

static int16_t read_demo(uint8_t id)
{
    kt_read(&fx, id, DEMO);
    return (int16_t)kt_read_le(&fx, DEMO);
}

static void write_demo(int16_t v)
{
    kt_write_u16(&fx, ID, DEMO, (uint16_t)v);
}

/* The row is in the table, named, with its hooks and its 0x83 sizes. */
static void test_row_in_the_generated_tables(void **state)
{
    (void)state;
    const int r = km_reg_find(DEMO);
    assert_true(r >= 0);
    assert_int_equal(km_reg_table[r].addr, DEMO);
    assert_int_equal(km_reg_table[r].access, KM_RW);
    assert_int_equal(km_reg_table[r].multi, KM_K(2));
    assert_string_equal(km_reg_names[r], "DEMO_ACCUMULATE");
    assert_ptr_equal(km_reg_read(r), km_rd_stored);
    assert_ptr_equal(km_reg_write(r), km_wr_demo_accumulate);
    assert_int_equal(km_reg_find(0x72), -1);
}

/* Read 0x02 answers its default; a write runs its hook (adds); a value
 * outside the .def's range, or a sum outside it, is bit 6 and changes
 * nothing; the super ID answers it in the own ID's slot. */
static void test_read_write_through_its_hook(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    assert_int_equal(read_demo(ID), 0);
    write_demo(5);
    write_demo(-2);
    assert_int_equal(read_demo(ID), 3);
    kt_ping_is(&fx, ID, 0);
    write_demo(1001);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    write_demo(998);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    assert_int_equal(read_demo(ID), 3);
    kt_read(&fx, KM_ID_SUPER, DEMO);
    assert_int_equal((int16_t)kt_read_le(&fx, DEMO), 3);
    assert_int_equal(fx.reply.delay_us, 200u + ID * kt_slot_us(9, 115200));
}

/* The sync write 0x04 takes it (a writable address) and 0x84 runs its hook. */
static void test_sync_write(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t body[3] = {DEMO, 7, 0};
    kt_send(&fx, ID, 0x04, body, sizeof body);
    kt_send_hex(&fx, "F9 FF FE 02 84 7B");
    kt_ping_is(&fx, ID, 0);
    assert_int_equal(read_demo(ID), 7);
}

/* 0x83 takes it with two-byte entries (its `multi` column) and refuses
 * other sizes (bit 6); the listed servo runs its entry through the hook. */
static void test_multi_write_by_its_column(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    const uint8_t m[] = {DEMO, 0x02, 1, 0x10, 0x00, ID, 0x09, 0x00, 5, 0x20, 0x00};
    kt_send(&fx, KM_ID_BROADCAST, 0x83, m, sizeof m);
    kt_ping_is(&fx, ID, 0);
    assert_int_equal(read_demo(ID), 9);
    const uint8_t bad[] = {DEMO, 0x01, ID, 0x09};
    kt_send(&fx, KM_ID_BROADCAST, 0x83, bad, sizeof bad);
    kt_ping_is(&fx, ID, KM_ST_FAILED);
    assert_int_equal(read_demo(ID), 9);
}

/* 0x82 reads it like 0x02, in the listed position's slot. */
static void test_multi_read(void **state)
{
    (void)state;
    kt_init(&fx, kt_product_pot(), ID);
    write_demo(-40);
    const uint8_t m[] = {DEMO, 1, 2, ID};
    kt_send(&fx, KM_ID_BROADCAST, 0x82, m, sizeof m);
    assert_int_equal((int16_t)kt_read_le(&fx, DEMO), -40);
    assert_int_equal(fx.reply.delay_us, 200u + 2u * kt_slot_us(9, 115200));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_row_in_the_generated_tables),
        cmocka_unit_test(test_read_write_through_its_hook),
        cmocka_unit_test(test_sync_write),
        cmocka_unit_test(test_multi_write_by_its_column),
        cmocka_unit_test(test_multi_read),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
