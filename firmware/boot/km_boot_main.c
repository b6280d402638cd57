/* SPDX-License-Identifier: Apache-2.0 */
/* The bootloader (docs/update.md §3): starts the application on trial
 * (§3a), else serves update mode. The board is behind km_boot_board.h. */
#include <stdbool.h>
#include <stdint.h>

#include "km_app_userdata.h"
#include "boot_layout.h"
#include "km_boot_address.h"
#include "km_boot_board.h"
#include "km_boot_check.h"
#include "km_boot_rx.h"
#include "km_boot_serve.h"
#include "km_parser.h"

#define PRV_ANSWER_DELAY_US 200u /* the 0x12 default: the master turns its line around */
#define PRV_KICK_US 50000u       /* watchdog reloads: 10 per 500 ms timeout */

/* An emulated bus's least gap (docs/architecture.md "The hal is hardware only"). */
#ifndef KM_BOOT_GAP_FLOOR_US
#define KM_BOOT_GAP_FLOOR_US 0
#endif

static km_boot_serve_t s_serve;
static km_boot_rx_t s_rx;
static km_boot_reply_t s_reply;
static uint32_t s_kicked_us; /* when the watchdog was last reloaded */

/* 0: no store reader (docs/update.md §3). */
#ifndef KM_BOOT_STORE_READER
#define KM_BOOT_STORE_READER 1
#endif

/* Waits until `us` after `from`. */
static void prv_wait_us(uint32_t from, uint32_t us)
{
    while (km_bootb_now_us() - from < us) {
    }
}

/* Reloads the watchdog every PRV_KICK_US (§3a). */
static void prv_kick(uint32_t now)
{
    if (now - s_kicked_us >= PRV_KICK_US) {
        s_kicked_us = now;
        km_bootb_watchdog_kick();
    }
}

/* Serves a frame: its answer after the delay, then any restart. */
static void prv_handle(const km_frame_view_t *v)
{
    km_boot_serve(&s_serve, v, &s_reply);
    if (s_reply.len > 0u) {
        prv_wait_us(v->end_tick, PRV_ANSWER_DELAY_US);
        km_bootb_uart_tx(s_reply.bytes, s_reply.len);
    }
    if (s_reply.action == KM_BOOT_ACT_RESTART) {
        km_bootb_reset();
    }
}

/* Starts the image if the checks (§3) and the trial (§3a) allow; else
 * returns whether it is valid, *asked whether update mode was asked for. */
static bool prv_boot(const km_image_target_t *t, km_image_header_t *h, bool *asked)
{
    volatile km_boot_shared_t *sh = km_bootb_shared();
    km_boot_entry_t e = {0u, 0u};
    const bool valid = km_boot_check(km_bootb_region(), t, h);
    const bool ok = valid && km_boot_entry(km_bootb_region(), h, BOOT_RAM_BASE, BOOT_SHARED_ADDR, &e);
    const km_boot_decision_t d = km_boot_decide(sh, ok);
    sh->boot_version = KM_BOOT_VERSION;
    sh->check = ~(uint32_t)KM_BOOT_VERSION;
    *asked = d == KM_BOOT_STAY_ASKED;
    if (d == KM_BOOT_RUN) {
        km_bootb_start(t->base + h->vectors, e.sp, e.pc);
    }
    return ok;
}

/* The boot decision, then update mode for ever. */
int main(void)
{
    km_bootb_init();
    km_bootb_factory();
    const km_image_target_t *t = km_bootb_target();
    km_image_header_t h;
    bool asked = false;
    const bool valid = prv_boot(t, &h, &asked);

    km_boot_address_t at;
    km_boot_address(km_bootb_shared(), asked, KM_BOOT_STORE_READER ? km_bootb_store() : 0,
                    KM_USERDATA_SCHEMA_VERSION, &at);
    uint8_t id = at.id;
    uint32_t baud = at.baud;
    if (!km_bootb_uart_init(baud)) {
        baud = KM_BOOT_FALLBACK_BAUD;
        (void)km_bootb_uart_init(baud);
    }
    km_update_init(&s_serve.upd, km_bootb_region(), t);
    s_serve.id = id;
    s_serve.shared = km_bootb_shared();
    s_serve.version = ((uint32_t)KM_BOOT_VERSION << 24) | (km_bootb_hw_version() << 16) |
                      (valid ? (h.version & 0xFFFFu) : 0u);
    uint32_t gap = km_parser_default_gap_us(baud);
#if KM_BOOT_GAP_FLOOR_US > 0
    if (gap < KM_BOOT_GAP_FLOOR_US) {
        gap = KM_BOOT_GAP_FLOOR_US;
    }
#endif
    km_boot_rx_init(&s_rx, gap);
    for (;;) {
        uint8_t b;
        km_frame_view_t v;
        const bool in = km_bootb_uart_rx(&b);
        const uint32_t now = km_bootb_now_us();
        prv_kick(now);
        const bool got = in ? km_boot_rx_feed(&s_rx, b, now, &v) : km_boot_rx_poll(&s_rx, now, &v);
        if (got) {
            prv_handle(&v);
        }
#ifdef BOOT_HAS_WAIT
        else if (!in) {
            km_bootb_wait();
        }
#endif
    }
}
