/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: the baud mismatch model (hs_wire.h). A sender puts each byte on
 * the wire as 8N1 at its bit time, back to back, idle (1) before and after;
 * the receiver waits for a falling edge, samples start, 8 data bits and stop
 * at their middles by its own clock, drops a byte whose stop bit reads 0
 * (framing error) and looks for the next edge from the stop bit's middle.
 * Times are integers in units of 1 / (2 x tx x rx) s: a sent bit is 2 x rx
 * units, a received bit 2 x tx units, exactly. */
#include "hs_wire.h"

#include <string.h>

#define HS_WIRE_BITS 10u /* start + 8 data + stop */

/* Bit k of the sent stream (0 = start of byte 0); idle 1 outside. */
static unsigned prv_bit(const uint8_t *in, size_t n, uint64_t k)
{
    const uint64_t byte = k / HS_WIRE_BITS;
    const unsigned pos = (unsigned)(k % HS_WIRE_BITS);
    if (byte >= n || pos == HS_WIRE_BITS - 1u) {
        return 1u;
    }
    if (pos == 0u) {
        return 0u;
    }
    return (in[byte] >> (pos - 1u)) & 1u;
}

static unsigned prv_level(const uint8_t *in, size_t n, uint64_t t, uint64_t t_tx)
{
    return prv_bit(in, n, t / t_tx);
}

size_t hs_wire_garble(const uint8_t *in, size_t n, uint32_t tx_baud, uint32_t rx_baud, uint8_t *out,
                      size_t out_cap)
{
    if (tx_baud == rx_baud || tx_baud == 0u || rx_baud == 0u) {
        const size_t len = n < out_cap ? n : out_cap;
        memcpy(out, in, len);
        return len;
    }
    const uint64_t t_tx = 2u * (uint64_t)rx_baud;
    const uint64_t t_rx = 2u * (uint64_t)tx_baud;
    const uint64_t nbits = (uint64_t)n * HS_WIRE_BITS;
    size_t got = 0;
    uint64_t t = 0;
    while (got < out_cap) {
        uint64_t k = (t + t_tx - 1u) / t_tx; /* the next bit boundary at or after t */
        while (k < nbits && !(prv_bit(in, n, k) == 0u && (k == 0u || prv_bit(in, n, k - 1u) == 1u))) {
            k++;
        }
        if (k >= nbits) {
            break;
        }
        const uint64_t mid = k * t_tx + t_rx / 2u;
        if (prv_level(in, n, mid, t_tx) != 0u) { /* a glitch, not a start bit */
            t = mid;
            continue;
        }
        unsigned value = 0;
        for (unsigned i = 0; i < 8u; i++) {
            value |= prv_level(in, n, mid + (uint64_t)(i + 1u) * t_rx, t_tx) << i;
        }
        const uint64_t stop_at = mid + 9u * t_rx;
        if (prv_level(in, n, stop_at, t_tx) == 1u) {
            out[got++] = (uint8_t)value;
        }
        t = stop_at;
        if (t >= nbits * t_tx) {
            break;
        }
    }
    return got;
}
