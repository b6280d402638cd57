/* SPDX-License-Identifier: Apache-2.0 */
/* 0x78 firmware update (docs/update.md), the application's side. */
#include <stddef.h>

#include "km_dispatch.h"
#include "km_encoder.h"

/* ENTER restarts into the bootloader, STATUS answers state 0, else bit 5; own ID only. */
km_report_t km_cmd_update(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    uint8_t body[KM_UPDATE_ANSWER_MAX];
    uint8_t n = 0u;
    const bool to_me = f->id == km_servo_id(s);
    if (s->ops == NULL || s->ops->update == NULL) {
        km_regfile_exception(&s->reg); /* like any command this firmware does not have */
        return KM_REPORT_NONE;
    }
    if (!s->ops->update(s->ops->ctx, f->body, f->body_len, body, &n)) {
        km_regfile_exception(&s->reg);
        if (!to_me) {
            return KM_REPORT_NONE;
        }
        km_dispatch_answer_status(s, km_regfile_own_status(&s->reg), f->id, reply);
        return KM_REPORT_OWN;
    }
    if (f->body_len >= 1u && f->body[0] == KM_UPDATE_SUB_ENTER) {
        s->restarting = true; /* an accepted ENTER is a restart: nothing after it runs */
        return KM_REPORT_NONE;
    }
    if (!to_me || n == 0u) {
        return KM_REPORT_NONE;
    }
    reply->len = km_encode_response(reply->bytes, km_servo_id(s), KM_CMD_UPDATE_FW, body, n);
    reply->delay_us = km_dispatch_delay_us(s, f->id, (uint16_t)(6u + n));
    return KM_REPORT_OWN;
}
