/* SPDX-License-Identifier: Apache-2.0 */
/* The extension command 0x7F (km_ext.h): 0x01..0x03 here, the rest through ops->ext_read. */
#include <stddef.h>

#include "km_dispatch.h"
#include "km_encoder.h"

/* The value of extension register `addr` into out, its length into *n;
 * false for an address nobody has (bit 5, like a read). */
static bool prv_ext_value(km_servo_t *s, uint8_t addr, uint8_t *out, uint8_t *n)
{
    switch (addr) {
    case KM_EXT_USERDATA_SOURCE:
        out[0] = s->userdata_source;
        *n = 1;
        return true;
    case KM_EXT_RESET_CAUSE:
        out[0] = s->reset_cause;
        *n = 1;
        return true;
    case KM_EXT_ACTIVE_BAUD:
        *n = km_put_le(out, s->active_baud / 100u, 2);
        return true;
    default:
        return s->ops != NULL && s->ops->ext_read != NULL && s->ops->ext_read(s->ops->ctx, addr, out, n) &&
               *n <= KM_EXT_VALUE_MAX;
    }
}

/* "Extension command 0x7F": the answer, at least 2 value bytes, same size for an address on every servo. */
km_report_t km_cmd_ext(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    uint8_t body[1 + KM_EXT_VALUE_MAX];
    uint8_t n = 0;
    const bool ok = f->body_len == 1 && prv_ext_value(s, f->body[0], &body[1], &n);
    if (!ok) {
        km_regfile_exception(&s->reg);
    }
    if (f->id == KM_ID_BROADCAST) {
        return KM_REPORT_NONE; /* run, never answered */
    }
    if (!ok) {
        km_dispatch_answer_status(s, km_regfile_own_status(&s->reg), f->id, reply);
    } else {
        body[0] = f->body[0];
        reply->len = km_encode_response(reply->bytes, km_servo_id(s), KM_CMD_EXT, body, (uint8_t)(1u + n));
        reply->delay_us = km_dispatch_delay_us(s, f->id, (uint16_t)(7u + (n > 2u ? n : 2u)));
    }
    return KM_REPORT_OWN;
}
