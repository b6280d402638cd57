/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: what a UART at one baud rate decodes from bytes sent at
 * another (the wire's baud mismatch model, docs/protocol-decisions.md "Baud
 * on the emulated bus"; the same algorithm as sim/bus/kmwire.py garble()). */
#ifndef HS_WIRE_H
#define HS_WIRE_H

#include <stddef.h>
#include <stdint.h>

/* At most this many bytes come out per byte in: one per falling edge, and
 * an 8N1 byte has at most 5 (its start bit and 4 inside the data). */
#define HS_WIRE_GROWTH 5u

/* Decodes `n` bytes sent back to back at tx_baud by a receiver at rx_baud
 * into out (room for out_cap bytes); framing errors are dropped. Returns the
 * bytes written. Equal rates copy. */
size_t hs_wire_garble(const uint8_t *in, size_t n, uint32_t tx_baud, uint32_t rx_baud, uint8_t *out,
                      size_t out_cap);

#endif
