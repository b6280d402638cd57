/* SPDX-License-Identifier: Apache-2.0 */
/* The bootloader's frame decoder (docs/update.md §1, §12): the parser's
 * frames, resync and gap rule (docs/protocol.md §2, §7), a byte at a time;
 * tests/unit/update/test_boot_rx.c checks it against the parser. */
#ifndef KM_BOOT_RX_H
#define KM_BOOT_RX_H

#include <stdbool.h>
#include <stdint.h>

#include "km_frame.h"

typedef struct {
    uint16_t n;          /* bytes held; buf[0] is the head candidate */
    uint16_t stale;      /* leading bytes received before a gap */
    uint16_t taken;      /* a handed-out frame's bytes, removed at the next call */
    uint32_t last;       /* tick of the newest byte */
    uint32_t stale_tick; /* tick of the newest byte before the gap */
    uint32_t gap;        /* a silence longer than this cuts (ticks) */
    uint8_t buf[KM_FRAME_MAX];
} km_boot_rx_t;

/* An empty decoder; a silence longer than `gap` ticks cuts. */
void km_boot_rx_init(km_boot_rx_t *rx, uint32_t gap);

/* One byte received at `now`. True: *out is a command frame, valid until
 * the next call. */
bool km_boot_rx_feed(km_boot_rx_t *rx, uint8_t byte, uint32_t now, km_frame_view_t *out);

/* No byte came: applies the gap, hands out a frame still waiting. */
bool km_boot_rx_poll(km_boot_rx_t *rx, uint32_t now, km_frame_view_t *out);

#endif
