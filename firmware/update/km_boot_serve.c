/* SPDX-License-Identifier: Apache-2.0 */
/* The bootloader's dispatcher (km_boot_serve.h). */
#include "km_boot_serve.h"

#include <string.h>

#include "km_encoder.h"
#include "km_update_proto.h"

#define PRV_CMD_PING 0x01u
#define PRV_CMD_READ 0x02u
#define PRV_CMD_WRITE 0x03u
#define PRV_REG_STATUS 0x01u
#define PRV_REG_RESTART 0x02u
#define PRV_REG_VERSION 0x0Cu
#define PRV_ST_EXCEPTION 0x20u

/* The short answer (docs/protocol.md §4): the status byte for the command, no body. */
static void prv_status_answer(km_boot_serve_t *s, km_boot_reply_t *r)
{
    r->len = km_encode_response(r->bytes, s->id, s->status, 0, 0u);
    s->status = 0u;
}

/* 0x02: the version (0x0C) or the status (0x01); anything else is bit 5. */
static void prv_read(km_boot_serve_t *s, const km_frame_view_t *f, int own, km_boot_reply_t *r)
{
    uint8_t body[5];
    uint8_t n;
    uint32_t value;
    const uint8_t reg = f->body_len == 1u ? f->body[0] : 0u;
    if (reg == PRV_REG_VERSION) {
        value = s->version;
        n = 5u;
    } else if (reg == PRV_REG_STATUS) {
        /* the status byte, then "random" byte 0 */
        value = s->status;
        n = 3u;
        s->status = 0u;
    } else {
        s->status |= PRV_ST_EXCEPTION;
        if (own) {
            prv_status_answer(s, r);
        }
        return;
    }
    body[0] = reg;
    for (uint32_t i = 0; i < 4u; i++) {
        body[1u + i] = (uint8_t)(value >> (8u * i));
    }
    if (own) {
        r->len = km_encode_response(r->bytes, s->id, PRV_CMD_READ, body, n);
    }
}

/* 0x78: the update's frames (km_update_proto.h). */
static void prv_update(km_boot_serve_t *s, const km_frame_view_t *f, int own, km_boot_reply_t *r)
{
    km_update_answer_t a;
    km_update_frame(&s->upd, f->body, f->body_len, &a);
    if (s->upd.state == KM_UPD_STATE_COMMITTED || a.action == KM_UPD_ACT_RESTART) {
        km_boot_trial_fresh(s->shared); /* a new image, or START: new tries */
    }
    if (a.action == KM_UPD_ACT_RESTART) {
        r->action = KM_BOOT_ACT_RESTART;
    } else if (a.action == KM_UPD_ACT_EXCEPTION) {
        s->status |= PRV_ST_EXCEPTION;
        if (own) {
            prv_status_answer(s, r);
        }
    } else if (own && a.len > 0u) {
        r->len = km_encode_response(r->bytes, s->id, KM_CMD_UPDATE, a.body, a.len);
    }
}

void km_boot_serve(km_boot_serve_t *s, const km_frame_view_t *f, km_boot_reply_t *r)
{
    r->len = 0u;
    r->action = KM_BOOT_ACT_NONE;
    const int own = f->id == s->id;
    if (!own && f->id != KM_ID_BROADCAST) {
        return;
    }
    switch (f->cmd) {
    case PRV_CMD_PING:
        if (f->body_len != 0u) {
            s->status |= PRV_ST_EXCEPTION;
        }
        if (own) {
            prv_status_answer(s, r);
        }
        return;
    case PRV_CMD_READ:
        prv_read(s, f, own, r);
        return;
    case PRV_CMD_WRITE: {
        static const uint8_t k_restart[5] = {PRV_REG_RESTART, 0xE1u, 0xE2u, 0xE3u, 0xE4u};
        if (f->body_len == 5u && memcmp(f->body, k_restart, 5u) == 0) {
            r->action = KM_BOOT_ACT_RESTART;
        } else {
            s->status |= PRV_ST_EXCEPTION; /* nothing else is writable here */
        }
        return;
    }
    case KM_CMD_UPDATE:
        prv_update(s, f, own, r);
        return;
    default:
        s->status |= PRV_ST_EXCEPTION;
        return;
    }
}
