/* SPDX-License-Identifier: Apache-2.0 */
/* The bootloader's frame decoder (docs/update.md §1, §3): the same frames
 * as the application's parser (protocol/km_parser.c, docs/protocol.md §2, §7):
 * F9 FF command frames with an addressable ID, length 2..252 and a good
 * checksum are handed out, F9 F5 responses from other servos are skipped
 * whole, after any failure the bytes already seen are rescanned from the
 * next F9 (a good frame right after garbage is kept), and a silence longer
 * than the gap drops a candidate that would need a byte from after it. A
 * byte at a time only, with none of the parser's batch shortcuts, counters
 * or checksum-error records (the bootloader reports none of them): a small
 * piece of code for the 4 KiB budget. tests/unit/update/test_boot_rx.c checks it
 * hands out exactly the parser's frames on random streams. */
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

void km_boot_rx_init(km_boot_rx_t *rx, uint32_t gap);

/* One byte received at `now`. True: *out is a command frame, a view into
 * rx valid until the next call. */
bool km_boot_rx_feed(km_boot_rx_t *rx, uint8_t byte, uint32_t now, km_frame_view_t *out);

/* Time alone: applies the gap, hands out a frame still waiting in the
 * bytes already seen. Call it whenever no byte came. */
bool km_boot_rx_poll(km_boot_rx_t *rx, uint32_t now, km_frame_view_t *out);

#endif
