/* SPDX-License-Identifier: Apache-2.0 */
/* Encoder tests: every response frame worked in docs/protocol.md §2, byte for byte. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "km_encoder.h"

/* §2: "its short response (status 0)  F9 F5 01 02 00 FC" */
static void test_s2_short_response_worked_frame(void **state)
{
    (void)state;
    uint8_t out[8];
    const uint8_t want[] = {0xF9, 0xF5, 0x01, 0x02, 0x00, 0xFC};
    assert_int_equal(km_encode_status(out, 1, 0), sizeof want);
    assert_memory_equal(out, want, sizeof want);
}

/* §2: "response: status 0, random 5  F9 F5 01 05 02 01 00 05 F1" */
static void test_s2_read_status_response_worked_frame(void **state)
{
    (void)state;
    uint8_t out[16];
    const uint8_t body[] = {0x01, 0x00, 0x05};
    const uint8_t want[] = {0xF9, 0xF5, 0x01, 0x05, 0x02, 0x01, 0x00, 0x05, 0xF1};
    assert_int_equal(km_encode_response(out, 1, 0x02, body, sizeof body), sizeof want);
    assert_memory_equal(out, want, sizeof want);
}

/* §2: a frame is at most 256 bytes; a longer body writes nothing. */
static void test_s2_response_longest_and_too_long(void **state)
{
    (void)state;
    static uint8_t body[KM_BODY_MAX + 1];
    static uint8_t out[KM_FRAME_MAX + 8];
    for (unsigned i = 0; i < sizeof out; i++) {
        out[i] = 0xAA;
    }
    assert_int_equal(km_encode_response(out, 7, 0x02, body, KM_BODY_MAX), KM_FRAME_MAX);
    assert_int_equal(out[3], KM_LENGTH_MAX);
    assert_int_equal(out[KM_FRAME_MAX], 0xAA); /* nothing past the frame */
    out[0] = 0x55;
    assert_int_equal(km_encode_response(out, 7, 0x02, body, (uint8_t)(KM_BODY_MAX + 1)), 0);
    assert_int_equal(out[0], 0x55);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s2_short_response_worked_frame),
        cmocka_unit_test(test_s2_read_status_response_worked_frame),
        cmocka_unit_test(test_s2_response_longest_and_too_long),
    };
    return cmocka_run_group_tests_name("encoder", tests, NULL, NULL);
}
