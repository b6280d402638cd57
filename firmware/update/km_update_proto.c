/* SPDX-License-Identifier: Apache-2.0 */
/* The 0x78 frames (km_update_proto.h, docs/update.md §4). */
#include "km_update_proto.h"

#include <string.h>

static const uint8_t k_enter_magic[4] = {0xB1u, 0xB2u, 0xB3u, 0xB4u};
static const uint8_t k_start_magic[4] = {0xE1u, 0xE2u, 0xE3u, 0xE4u};

/* The little-endian value of n bytes. */
static uint32_t prv_le(const uint8_t *p, uint32_t n)
{
    uint32_t v = 0u;
    for (uint32_t i = n; i-- > 0u;) {
        v = (v << 8) | p[i];
    }
    return v;
}

/* v's low 16 bits, little-endian. */
static void prv_put16(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

/* The two-byte answer: sub, result. */
static void prv_answer(km_update_answer_t *a, uint8_t sub, uint8_t result)
{
    a->body[0] = sub;
    a->body[1] = result;
    a->len = 2u;
}

/* STATUS answer: sub, state, result, blocks, received, first, bitmap. */
static void prv_status(uint8_t state, uint8_t result, const km_update_t *u, const uint8_t *p, uint8_t n,
                       km_update_answer_t *a)
{
    const uint32_t blocks = u != NULL ? u->blocks : 0u;
    uint32_t first = n == 2u ? prv_le(p, 2) : 0u;
    uint8_t count = 0u;
    if (n != 2u || first % 8u != 0u || (first >= blocks && first != 0u)) {
        result = KM_UPD_BAD_LENGTH;
    } else if (u != NULL && blocks > 0u) {
        uint32_t bytes = (blocks - first + 7u) / 8u;
        count = (uint8_t)(bytes < KM_UPD_STATUS_BITMAP_MAX ? bytes : KM_UPD_STATUS_BITMAP_MAX);
        memcpy(&a->body[9], &u->bitmap[first / 8u], count);
    }
    a->body[0] = KM_UPD_SUB_STATUS;
    a->body[1] = state;
    a->body[2] = result;
    prv_put16(&a->body[3], blocks);
    prv_put16(&a->body[5], u != NULL ? u->received : 0u);
    prv_put16(&a->body[7], n == 2u ? first : 0u);
    a->len = (uint8_t)(9u + count);
}

/* WRITE: block number, the block, its CRC; answered with the block number. */
static void prv_write(km_update_t *u, const uint8_t *p, uint8_t np, km_update_answer_t *a)
{
    km_update_result_t r;
    if (np != 2u + KM_UPDATE_BLOCK + 4u) {
        r = KM_UPD_BAD_LENGTH;
    } else {
        r = km_update_write(u, prv_le(p, 2), p + 2, prv_le(p + 2 + KM_UPDATE_BLOCK, 4));
    }
    prv_answer(a, KM_UPD_SUB_WRITE, (uint8_t)r);
    a->body[2] = np >= 2u ? p[0] : 0u;
    a->body[3] = np >= 2u ? p[1] : 0u;
    a->len = 4u;
    u->result = (uint8_t)r;
}

/* VERIFY: the image's CRC in the answer. */
static void prv_verify(km_update_t *u, uint8_t np, km_update_answer_t *a)
{
    uint32_t crc = 0u;
    const km_update_result_t r = np == 0u ? km_update_verify(u, &crc) : KM_UPD_BAD_LENGTH;
    u->result = (uint8_t)r;
    prv_answer(a, KM_UPD_SUB_VERIFY, (uint8_t)r);
    for (uint32_t i = 0; i < 4u; i++) {
        a->body[2u + i] = (uint8_t)(crc >> (8u * i));
    }
    a->len = 6u;
}

void km_update_frame(km_update_t *u, const uint8_t *body, uint8_t n, km_update_answer_t *a)
{
    a->len = 0u;
    a->action = KM_UPD_ACT_NONE;
    if (n < 1u) {
        a->action = KM_UPD_ACT_EXCEPTION;
        return;
    }
    const uint8_t sub = body[0];
    const uint8_t *p = body + 1;
    const uint8_t np = (uint8_t)(n - 1u);
    km_update_result_t r;
    switch (sub) {
    case KM_UPD_SUB_ENTER:
        if (np != 4u || memcmp(p, k_enter_magic, 4u) != 0) {
            u->result = KM_UPD_BAD_MAGIC;
        } else {
            km_update_reset(u);
        }
        return; /* never answered, like restart */
    case KM_UPD_SUB_BEGIN:
        r = np == KM_IMAGE_HEADER_SIZE ? km_update_begin(u, p) : KM_UPD_BAD_LENGTH;
        break;
    case KM_UPD_SUB_WRITE:
        prv_write(u, p, np, a);
        return;
    case KM_UPD_SUB_STATUS:
        prv_status(u->state, u->result, u, p, np, a);
        return;
    case KM_UPD_SUB_VERIFY:
        prv_verify(u, np, a);
        return;
    case KM_UPD_SUB_COMMIT:
        r = np == 0u ? km_update_commit(u) : KM_UPD_BAD_LENGTH;
        break;
    case KM_UPD_SUB_START:
        if (np != 4u || memcmp(p, k_start_magic, 4u) != 0) {
            r = KM_UPD_BAD_MAGIC;
            break;
        }
        a->action = KM_UPD_ACT_RESTART;
        return;
    default:
        a->action = KM_UPD_ACT_EXCEPTION;
        return;
    }
    u->result = (uint8_t)r;
    prv_answer(a, sub, (uint8_t)r);
}

void km_update_app_frame(const uint8_t *body, uint8_t n, km_update_answer_t *a)
{
    a->len = 0u;
    a->action = KM_UPD_ACT_NONE;
    if (n >= 1u && body[0] == KM_UPD_SUB_ENTER) {
        if (n == 5u && memcmp(body + 1, k_enter_magic, 4u) == 0) {
            a->action = KM_UPD_ACT_ENTER;
        } else {
            a->action = KM_UPD_ACT_EXCEPTION; /* bad magic: nothing happens (bit 5) */
        }
        return;
    }
    if (n >= 1u && body[0] == KM_UPD_SUB_STATUS) {
        prv_status(KM_UPD_STATE_APP, KM_UPD_OK, NULL, body + 1, (uint8_t)(n - 1u), a);
        return;
    }
    a->action = KM_UPD_ACT_EXCEPTION;
}
