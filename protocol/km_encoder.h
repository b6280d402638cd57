/* SPDX-License-Identifier: Apache-2.0 */
/* Encoder for servo -> master frames (docs/protocol.md §2): the response frame
 * `F9 F5 id len cmd body... cs` and the short status frame `F9 F5 id 02 st cs`. */
#ifndef KM_ENCODER_H
#define KM_ENCODER_H

#include <stdint.h>

#include "km_frame.h"

/* Writes a response frame into `out` (at least body_len + 6 bytes; never more
 * than KM_FRAME_MAX). Returns the frame's size in bytes, or 0 if body_len
 * exceeds KM_BODY_MAX (nothing written). */
uint16_t km_encode_response(uint8_t *out, uint8_t id, uint8_t cmd, const uint8_t *body, uint8_t body_len);

/* Writes the 6-byte short response. Returns 6. */
uint16_t km_encode_status(uint8_t *out, uint8_t id, uint8_t status);

#endif
