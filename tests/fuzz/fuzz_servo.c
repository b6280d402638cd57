/* libFuzzer target for parser + dispatcher together: bus bytes in, answers
 * out, exactly as the firmware wires them (PROTOCOL.md §2-§5).
 *
 * Input: the same format as fuzz_parser.c (byte 0 gap, byte 1 start tick,
 * then (byte, control) pairs; control's top bits: 00 advance, 01 advance and
 * poll, 10 overrun, 11 tick jump), so the §2 seed corpus serves both. Byte 0
 * also picks the product variant (bit 4) and whether commits fail (bit 5).
 *
 * Invariants (abort() on violation):
 *  - an answer is a well-formed F9 F5 frame (length, checksum) of at most
 *    256 bytes, carries the ID the servo had when the frame arrived, and is
 *    never given to a broadcast frame or to a frame for another ID;
 *  - every register the servo stores passes its own validation: no write,
 *    however malformed, stores an out-of-range value (§4: a rejected write
 *    changes nothing);
 *  - commits name only persisted registers; a failed commit changes none of
 *    them;
 *  - a restart re-initialises from what was committed, and the servo keeps
 *    working. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "km_parser.h"
#include "km_servo.h"

static const km_product_t s_products[2] = {
    {.model = "FUZZ-POT", .firmware_version = 0x00100100u, .variant = KM_VARIANT_POTENTIOMETER,
     .max_current_ma = 2000, .max_speed_dps = 360, .zero_offset1 = 12, .angle_min = -1350,
     .angle_max = 1350, .voltage_high_v = 9, .voltage_low_v = 6, .current_threshold_ma = 1500,
     .baud_min_100 = 96, .baud_max_100 = 10000, .current_max_ma = 3000, .speed_max_dps = 720,
     .travel_min = -1350, .travel_max = 1350, .zero_offset2_max = 100, .voltage_max_v = 20},
    {.model = "FUZZ-ENCODER-16CH", .firmware_version = 0x52111002u, .variant = KM_VARIANT_ENCODER,
     .max_current_ma = 3000, .max_speed_dps = 600, .zero_offset1 = 0, .angle_min = 0,
     .angle_max = 0, .voltage_high_v = 14, .voltage_low_v = 9, .current_threshold_ma = 2500,
     .baud_min_100 = 96, .baud_max_100 = 10000, .current_max_ma = 5000, .speed_max_dps = 1000,
     .travel_min = -32768, .travel_max = 32767, .zero_offset2_max = 1800, .voltage_max_v = 30},
};

static km_servo_t s_servo;
static const km_product_t *s_product;
static uint32_t s_persisted[KM_REG_COUNT];
static bool s_commit_fails;
static bool s_restart;

static bool prv_commit(void *ctx, const uint8_t *addrs, const uint32_t *values, uint8_t n)
{
    (void)ctx;
    for (uint8_t i = 0; i < n; i++) {
        const int r = km_reg_find(addrs[i]);
        if (r < 0 || !km_reg_table[r].persisted) {
            abort();
        }
    }
    if (s_commit_fails) {
        return false;
    }
    for (uint8_t i = 0; i < n; i++) {
        s_persisted[km_reg_find(addrs[i])] = values[i];
    }
    return true;
}

static void prv_restart(void *ctx)
{
    (void)ctx;
    s_restart = true;
}

static void prv_request(void *ctx, const km_request_t *req)
{
    (void)ctx;
    if ((unsigned)req->kind > (unsigned)KM_REQ_PROTECTION_CLEAR) {
        abort();
    }
}

static const km_servo_ops_t s_ops = {prv_commit, prv_restart, prv_request, NULL};

static void prv_boot(uint32_t seed)
{
    uint32_t p[KM_REG_COUNT];
    uint8_t k = 0;
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        if (km_reg_table[i].persisted) {
            p[k++] = s_persisted[i];
        }
    }
    km_servo_init(&s_servo, s_product, p, seed, &s_ops);
}

static void prv_check_registers(void)
{
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        const km_reg_t *r = &km_reg_table[i];
        const uint8_t size = km_reg_fixed_size((km_layout_t)r->layout);
        if (r->access != KM_RW || size == 0 || i == KM_REG_PROT_FLAGS) {
            continue; /* read-only, write-only actions, write-1-to-clear: nothing stored */
        }
        uint8_t bytes[4];
        uint32_t packed;
        km_put_le(bytes, km_servo_reg(&s_servo, (km_reg_index_t)i), size);
        if (!km_reg_validate((km_reg_index_t)i, s_product, bytes, size, &packed)) {
            abort();
        }
        if (r->persisted && km_servo_reg(&s_servo, (km_reg_index_t)i) != s_persisted[i]) {
            abort(); /* RAM and flash disagree: a failed commit leaked */
        }
    }
}

static void prv_check_answer(const km_frame_t *f, uint8_t id_before, const km_reply_t *reply)
{
    if (reply->len == 0) {
        return;
    }
    if (f->id == KM_ID_BROADCAST || (f->id != id_before && f->id != KM_ID_SUPER)) {
        abort();
    }
    const uint8_t *b = reply->bytes;
    if (reply->len > KM_FRAME_MAX || reply->len < 6 || b[0] != KM_HDR0 || b[1] != KM_HDR1_RESPONSE ||
        b[2] != id_before || b[3] + 4u != reply->len ||
        km_checksum(&b[2], (uint32_t)reply->len - 3u) != b[reply->len - 1u]) {
        abort();
    }
}

static void prv_dispatch(unsigned events, km_frame_t *frame, km_parser_t *parser, uint32_t seed)
{
    if ((events & KM_PARSE_CHECKSUM_ERR) && km_parser_take_checksum_error(parser, km_servo_id(&s_servo))) {
        km_servo_note_checksum_error(&s_servo);
    }
    if (!(events & KM_PARSE_FRAME)) {
        return;
    }
    static km_reply_t reply;
    const uint8_t id_before = km_servo_id(&s_servo);
    km_servo_handle(&s_servo, frame, &reply);
    prv_check_answer(frame, id_before, &reply);
    prv_check_registers();
    if (s_restart) {
        s_restart = false;
        prv_boot(seed);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2) {
        return 0;
    }
    s_product = &s_products[(data[0] >> 4) & 1u];
    s_commit_fails = (data[0] & 0x20u) != 0;
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        s_persisted[i] = km_reg_default((km_reg_index_t)i, s_product);
    }
    s_persisted[KM_REG_ID] = 1; /* the §2 worked frames talk to ID 1 */
    const uint32_t seed = 175u + data[1];
    prv_boot(seed);

    static km_parser_t parser;
    static km_frame_t frame;
    km_parser_init(&parser, (uint32_t)(data[0] & 0x0Fu) + 1u);
    uint32_t tick = 0xFFFFFF00u + data[1];
    for (size_t i = 2; i + 1 < size; i += 2) {
        const uint8_t ctl = data[i + 1];
        switch (ctl >> 6) {
        case 0:
            tick += ctl & 0x3Fu;
            break;
        case 1:
            tick += ctl & 0x3Fu;
            prv_dispatch(km_parser_poll(&parser, tick, &frame), &frame, &parser, seed);
            break;
        case 2:
            km_parser_overrun(&parser);
            break;
        default:
            tick += (uint32_t)(ctl & 0x3Fu) << 26;
            break;
        }
        prv_dispatch(km_parser_feed(&parser, data[i], tick, &frame), &frame, &parser, seed);
    }
    for (int n = 0; n < 4; n++) {
        tick += 1000u;
        prv_dispatch(km_parser_poll(&parser, tick, &frame), &frame, &parser, seed);
    }
    return 0;
}
