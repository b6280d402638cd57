/* SPDX-License-Identifier: Apache-2.0 */
/* Frame constants and the decoded command frame shared by parser, dispatcher
 * and encoder (docs/protocol.md §1, §2). */
#ifndef KM_FRAME_H
#define KM_FRAME_H

#include <stdint.h>

#define KM_HDR0 0xF9u          /* first header byte of every frame */
#define KM_HDR1_COMMAND 0xFFu  /* master -> servo */
#define KM_HDR1_RESPONSE 0xF5u /* servo -> master */

#define KM_FRAME_MAX 256u  /* whole frame, header to checksum (§2) */
#define KM_LENGTH_MIN 2u   /* ping, 0x84, short response */
#define KM_LENGTH_MAX 252u /* KM_FRAME_MAX - header(2) - id - length */
/* Bytes after the command byte and before the checksum: address + params. */
#define KM_BODY_MAX (KM_LENGTH_MAX - 2u)

#define KM_ID_MAX 250u        /* servo IDs are 0..250 (§1) */
#define KM_ID_SUPER 0xFDu     /* every servo answers in its slot */
#define KM_ID_BROADCAST 0xFEu /* every servo executes, none answers */

/* A command frame that passed header, length and checksum checks. The parser
 * knows no command: `body` is everything between the command byte and the
 * checksum (for most commands body[0] is the register address). */
typedef struct {
    uint8_t id;
    uint8_t cmd;
    uint8_t body_len; /* = length - 2 */
    uint8_t body[KM_BODY_MAX];
    uint32_t end_tick; /* caller's tick of the frame's last byte */
} km_frame_t;

/* The same frame as the dispatcher reads it: the body is wherever it
 * already is (the parser's ring, or a km_frame_t's body), not a copy. */
typedef struct {
    uint8_t id;
    uint8_t cmd;
    uint8_t body_len;
    const uint8_t *body; /* body_len bytes */
    uint32_t end_tick;
} km_frame_view_t;

/* The §2 checksum over `n` bytes (ID through last parameter). */
static inline uint8_t km_checksum(const uint8_t *bytes, uint32_t n)
{
    uint32_t sum = 0;
    for (uint32_t i = 0; i < n; i++) {
        sum += bytes[i];
    }
    return (uint8_t)~sum;
}

/* True for an ID byte a command frame may carry: 0..250, 253, 254. */
static inline int km_id_is_addressable(uint8_t id)
{
    return id <= KM_ID_MAX || id == KM_ID_SUPER || id == KM_ID_BROADCAST;
}

#endif
