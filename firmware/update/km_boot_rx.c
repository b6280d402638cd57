/* SPDX-License-Identifier: Apache-2.0 */
/* The bootloader's frame decoder (km_boot_rx.h): one array, the head
 * candidate at buf[0]; one frame per call (docs/update.md §12). */
#include "km_boot_rx.h"

#include <string.h>

void km_boot_rx_init(km_boot_rx_t *rx, uint32_t gap)
{
    memset(rx, 0, sizeof *rx);
    rx->gap = gap;
}

/* Drops the first k bytes held. */
static void prv_drop(km_boot_rx_t *rx, uint16_t k)
{
    rx->n = (uint16_t)(rx->n - k);
    memmove(rx->buf, rx->buf + k, rx->n);
    rx->stale = rx->stale > k ? (uint16_t)(rx->stale - k) : 0u;
}

/* The head candidate's n bytes break a header rule of the parser. */
static bool prv_header_bad(const uint8_t *h, uint16_t n)
{
    return h[0] != KM_HDR0 || (n > 1u && h[1] != KM_HDR1_COMMAND && h[1] != KM_HDR1_RESPONSE) ||
           (n > 2u && (h[1] == KM_HDR1_COMMAND ? !km_id_is_addressable(h[2]) : h[2] > KM_ID_MAX)) ||
           (n > 3u && (h[3] < KM_LENGTH_MIN || h[3] > KM_LENGTH_MAX));
}

/* 0: good so far, incomplete; 1: failed; else its length (complete, checksum good). */
static uint16_t prv_judge(const km_boot_rx_t *rx)
{
    const uint8_t *h = rx->buf;
    const uint16_t n = rx->n;
    if (prv_header_bad(h, n)) {
        return 1u;
    }
    const uint16_t need = n > 3u ? (uint16_t)(h[3] + 4u) : 0u;
    if (rx->stale != 0u && (need == 0u || need > rx->stale)) {
        return 1u; /* it would need a byte from after the gap */
    }
    if (need == 0u || n < need) {
        return 0u;
    }
    return km_checksum(h + 2, need - 3u) == h[need - 1u] ? need : 1u;
}

/* Drops failed candidates and other servos' answers; true: *out is a frame. */
static bool prv_settle(km_boot_rx_t *rx, km_frame_view_t *out)
{
    while (rx->n != 0u) {
        const uint16_t len = prv_judge(rx);
        if (len == 0u) {
            return false;
        }
        if (len == 1u) {
            prv_drop(rx, 1u);
        } else if (rx->buf[1] == KM_HDR1_RESPONSE) {
            prv_drop(rx, len); /* another servo's answer, skipped whole */
        } else {
            /* A frame from before a gap ends no later than the cut. */
            *out = (km_frame_view_t){rx->buf[2], rx->buf[4], (uint8_t)(len - 6u), rx->buf + 5,
                                     rx->stale != 0u ? rx->stale_tick : rx->last};
            rx->taken = len;
            return true;
        }
    }
    return false;
}

/* Removes the frame handed out last time, then applies the gap. */
static void prv_begin(km_boot_rx_t *rx, uint32_t now)
{
    if (rx->taken != 0u) {
        prv_drop(rx, rx->taken);
        rx->taken = 0u;
    }
    if (rx->n != 0u && (uint32_t)(now - rx->last) > rx->gap) {
        if (rx->stale == 0u) {
            rx->stale = rx->n;
            rx->stale_tick = rx->last;
        } else {
            /* A second cut before the first one's bytes were judged: the
             * bytes between go, so no frame spans a cut. */
            rx->n = rx->stale;
        }
    }
}

bool km_boot_rx_feed(km_boot_rx_t *rx, uint8_t byte, uint32_t now, km_frame_view_t *out)
{
    prv_begin(rx, now);
    rx->last = now;
    if (rx->n < KM_FRAME_MAX) {
        rx->buf[rx->n++] = byte;
    }
    return prv_settle(rx, out);
}

bool km_boot_rx_poll(km_boot_rx_t *rx, uint32_t now, km_frame_view_t *out)
{
    prv_begin(rx, now);
    return prv_settle(rx, out);
}
