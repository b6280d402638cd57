/* SPDX-License-Identifier: Apache-2.0 */
/* libFuzzer target for the servo as the firmware wires it: bytes on a wire
 * into the real main loop (firmware/app/km_app.c: RX queue, parser,
 * checksum hand-off, dispatcher, answer timer, store on the NOR simulator,
 * restarts), over the fake board of tests/support/km_fake_hal.h in virtual
 * time (docs/protocol.md §2-§5).
 *
 * Input: byte 0 picks the servo's starting ID (low bits: 0 or 1, so the §2
 * worked frames of the seed corpus address it) and the UART delivery floor
 * (bit 4); byte 1 is unused (kept so the corpus of fuzz_parser serves
 * both); then (byte, control) pairs: control's top bits 00 = the byte
 * follows at line rate plus (control & 0x3F) us, 01 = plus that many ms,
 * 10 = plus that many x 10 ms (long gaps, restarts), 11 = the servo resets
 * (pin) before the byte.
 *
 * Invariants (abort() on violation):
 *  - everything the servo puts on the wire is whole F9 F5 frames with valid
 *    checksums, and none overlaps another (one answer at a time);
 *  - the main loop never spins and the watchdog never fires; the UART never
 *    refuses an answer;
 *  - every register the servo stores passes its own validation, and the
 *    user data in RAM is what a reset reads back from flash;
 *  - bits 5/6 are never reported twice: of two pings in a row, the second
 *    answers with bits 5 and 6 clear; and the servo still answers. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "km_app.h"
#include "km_fake_hal.h"
#include "km_frame.h"
#include "km_registers.h"

static void prv_check(int ok)
{
    if (!ok) {
        abort();
    }
}

static uint8_t prv_sum(const uint8_t *b, unsigned n)
{
    unsigned s = 0;
    for (unsigned i = 0; i < n; i++) {
        s += b[i];
    }
    return (uint8_t)~s;
}

/* Everything sent so far is whole, valid frames; returns the count. */
static unsigned prv_check_wire(uint8_t *last_status)
{
    static uint8_t w[KF_TX_MAX];
    const unsigned n = kf_take_tx(w, sizeof w);
    unsigned frames = 0;
    for (unsigned i = 0; i < n;) {
        prv_check(i + 4u <= n && w[i] == KM_HDR0 && w[i + 1] == KM_HDR1_RESPONSE);
        const unsigned len = w[i + 3];
        prv_check(len >= 2u && i + 4u + len <= n);
        prv_check(w[i + 3 + len] == prv_sum(&w[i + 2], len + 1u));
        if (len == 2u && last_status) {
            *last_status = w[i + 4];
        }
        i += 4u + len;
        frames++;
    }
    return frames;
}

static void prv_check_registers(void)
{
    const km_servo_t *s = km_app_servo();
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        const km_reg_t *r = &km_reg_table[i];
        const uint8_t size = km_reg_fixed_size((km_layout_t)r->layout);
        if (r->access != KM_RW || size == 0 || i == KM_REG_PROT_FLAGS) {
            continue; /* read-only, write-only actions, write-1-to-clear: nothing stored */
        }
        uint8_t bytes[4];
        uint32_t packed;
        km_put_le(bytes, km_servo_reg(s, (km_reg_index_t)i), size);
        prv_check(km_reg_validate((km_reg_index_t)i, s->reg.product, bytes, size, &packed));
    }
}

static void prv_run(uint32_t us)
{
    prv_check(kf_run_for(us));
    prv_check(!kf_world.spun && kf_world.watchdog_resets == 0);
    prv_check(km_app_tx_refused() == 0 && kf_world.tx_refused == 0);
}

/* Runs until the wire is quiet: every byte delivered, no answer armed or
 * on the wire (an answer may be a response delay of up to 65 ms away). */
static void prv_settle(void)
{
    for (int i = 0; i < 200; i++) {
        prv_run(1000);
        if (kf_world.rx_head == kf_world.rx_n && !kf_world.timer_armed && !kf_world.tx_buf) {
            prv_run(2000); /* past any inter-byte gap and a restart */
            return;
        }
    }
}

static void prv_ping(uint8_t id)
{
    uint8_t f[6] = {KM_HDR0, KM_HDR1_COMMAND, id, 0x02, 0x01, 0};
    f[5] = prv_sum(&f[2], 3);
    kf_send_at(kf_world.now, f, sizeof f);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2) {
        return 0;
    }
    kf_power_on();
    kf_world.gap_floor_us = (data[0] & 0x10u) ? 20000u : 0u;
    if (data[0] & 0x01u) { /* start as ID 1: the worked frames' ID */
        const uint8_t set_id[] = {0xF9, 0xFF, 0x00, 0x04, 0x03, 0x0F, 0x01, 0xE8};
        kf_send_at(kf_world.now, set_id, sizeof set_id);
    }
    kf_boot(KM_RESET_POWER_ON);
    prv_settle();

    uint32_t at = kf_world.now;
    for (size_t i = 2; i + 1 < size; i += 2) {
        const uint8_t ctl = data[i + 1];
        const uint32_t v = ctl & 0x3Fu;
        switch (ctl >> 6) {
        case 0:
            at += v;
            break;
        case 1:
            at += v * 1000u;
            break;
        case 2:
            at += v * 10000u;
            break;
        default:
            prv_run(at - kf_world.now > 0x7FFFFFFFu ? 0u : at - kf_world.now);
            kf_boot(KM_RESET_PIN);
            at = kf_world.now;
            break;
        }
        kf_send_at(at, &data[i], 1);
        at = kf_world.now > at ? kf_world.now : at;
        at += kf_byte_us();
    }
    /* Let everything land, every answer and restart finish. */
    prv_run(at > kf_world.now ? at - kf_world.now : 0u);
    prv_settle();
    (void)prv_check_wire(NULL);
    prv_check_registers();

    /* RAM equals flash: a reset reads back exactly the user data in force. */
    const km_servo_t *s = km_app_servo();
    uint32_t before[KM_REG_COUNT];
    memcpy(before, s->reg.value, sizeof before);
    kf_boot(KM_RESET_PIN);
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        if (km_reg_table[i].persisted) {
            prv_check(s->reg.value[i] == before[i]);
        }
    }

    /* Two pings: the second reports no bit 5/6 (never told twice). */
    const uint8_t id = km_servo_id(s);
    prv_ping(id);
    prv_settle();
    prv_ping(id);
    prv_settle();
    uint8_t status = 0xFF;
    prv_check(prv_check_wire(&status) == 2u);
    prv_check((status & 0x60u) == 0u);
    return 0;
}
