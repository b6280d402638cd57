/* SPDX-License-Identifier: Apache-2.0 */
/* Encoder for servo -> master frames (docs/protocol.md §2). */
#include "km_encoder.h"

/* km_encode_response one call in the 32 KiB build (KM_PROTOCOL_COMPACT: docs/footprint.md). */
#if defined(KM_PROTOCOL_COMPACT) && KM_PROTOCOL_COMPACT
#define PRV_ENCODE_NOINLINE __attribute__((noinline))
#else
#define PRV_ENCODE_NOINLINE
#endif

PRV_ENCODE_NOINLINE uint16_t km_encode_response(uint8_t *out, uint8_t id, uint8_t cmd, const uint8_t *body,
                                                uint8_t body_len)
{
    if (body_len > KM_BODY_MAX) {
        return 0;
    }
    const uint8_t length = (uint8_t)(body_len + 2u); /* cmd + body + checksum */
    out[0] = KM_HDR0;
    out[1] = KM_HDR1_RESPONSE;
    out[2] = id;
    out[3] = length;
    out[4] = cmd;
    /* Checksum (§2) covers ID through the last body byte: summed as the body is copied. */
    uint32_t sum = (uint32_t)id + length + cmd;
    for (uint8_t i = 0; i < body_len; i++) {
        const uint8_t byte = body[i];
        out[5u + i] = byte;
        sum += byte;
    }
    out[5u + body_len] = (uint8_t)~sum;
    return (uint16_t)(6u + body_len);
}

uint16_t km_encode_status(uint8_t *out, uint8_t id, uint8_t status)
{
    out[0] = KM_HDR0;
    out[1] = KM_HDR1_RESPONSE;
    out[2] = id;
    out[3] = 2u;
    out[4] = status;
    out[5] = km_checksum(&out[2], 3u);
    return 6u;
}
