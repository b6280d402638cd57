/* SPDX-License-Identifier: Apache-2.0 */
/* Dispatcher (docs/protocol.md §3 commands, §4 status, §5 registers): ID rules, then the command table; ping,
 * read, write and the sync write. */
#include "km_servo.h"

#include <string.h>

#include "km_dispatch.h"
#include "km_encoder.h"
#include "km_hooks.h"

enum {
    CMD_PING = 0x01,
    CMD_READ = 0x02,
    CMD_WRITE = 0x03,
    CMD_SYNC_WRITE = 0x04,
    CMD_MULTI_READ = 0x82,
    CMD_MULTI_WRITE = 0x83,
    CMD_SYNC_EXECUTE = 0x84,
};

#define CONFIG_RESPONSE_LEVEL 0x08u
#define TEXT_MAX 16u

/* What the ID rules need to know of a command. */
enum {
    RULE_SUPER = 0x01,     /* "Super ID": answered at the super ID (a query) */
    RULE_BROADCAST = 0x02, /* "Multi-ID ...": sent to the broadcast ID only */
    RULE_KEEPS_SYNC = 0x04 /* §3: leaves the 0x04 buffer alone (0x04, 0x84) */
};

typedef struct {
    uint8_t cmd;
    uint8_t rules;
    km_command_fn run;
} prv_command_t;

/* clang-format off */
#if KM_PROTOCOL_COMPACT
/* §3 and this firmware's own commands, searched in order (the compact build):
 * 0x83 first, the command whose longest frames leave the least time to its
 * answer slot (docs/footprint.md "The 32 KiB image on time"). */
#define PRV_SLOT(cmd)
static const prv_command_t s_commands[] = {
    {CMD_MULTI_WRITE, RULE_BROADCAST | RULE_KEEPS_SYNC, km_cmd_multi_write},
#else
/* §3 and this firmware's own commands, indexed by the command byte's bit 7 and low three bits. */
#define PRV_SLOT_OF(cmd) ((((unsigned)(cmd) >> 4) & 8u) | ((unsigned)(cmd)&7u))
#define PRV_SLOT(cmd) [PRV_SLOT_OF(cmd)] =

static const prv_command_t s_commands[16] = {
#endif
    PRV_SLOT(CMD_PING) {CMD_PING, RULE_SUPER, km_cmd_ping},
    PRV_SLOT(CMD_READ) {CMD_READ, RULE_SUPER, km_cmd_read},
    PRV_SLOT(CMD_WRITE) {CMD_WRITE, 0, km_cmd_write},
    PRV_SLOT(CMD_SYNC_WRITE) {CMD_SYNC_WRITE, RULE_KEEPS_SYNC, km_cmd_sync_write},
    PRV_SLOT(CMD_SYNC_EXECUTE) {CMD_SYNC_EXECUTE, RULE_KEEPS_SYNC, km_cmd_sync_execute},
#if KM_FEATURE_MULTI_READ
    PRV_SLOT(CMD_MULTI_READ) {CMD_MULTI_READ, RULE_BROADCAST | RULE_KEEPS_SYNC, km_cmd_multi_read},
#endif
#if !KM_PROTOCOL_COMPACT
    PRV_SLOT(CMD_MULTI_WRITE) {CMD_MULTI_WRITE, RULE_BROADCAST | RULE_KEEPS_SYNC, km_cmd_multi_write},
#endif
#if KM_FEATURE_EXT
    PRV_SLOT(KM_CMD_EXT) {KM_CMD_EXT, RULE_SUPER, km_cmd_ext},
#endif
    PRV_SLOT(KM_CMD_UPDATE_FW) {KM_CMD_UPDATE_FW, 0, km_cmd_update},
};
/* clang-format on */

/* ---- answer timing ------------------------------------------------------ */

/* "Super-ID answer slots": servo i starts response_delay + i * slot after the frame. */
static uint32_t prv_slot_us(const km_servo_t *s, uint16_t answer_bytes)
{
    /* ceil(n x 1e7 / baud), n = answer_bytes + 2, without a division (a
     * library call on the M0; 0x82 pays it per answer): n x q + ceil(n x r
     * / baud). t estimates n x r / baud from below (byte_us_f is floored)
     * and rises to the ceiling in a step or two. */
    const uint32_t n = (uint32_t)answer_bytes + 2u;
    const uint32_t nr = n * s->byte_us_r;
    uint32_t t = (n * s->byte_us_f) >> 12;
    while (t * s->active_baud < nr) {
        t++;
    }
    const uint32_t slot = n * s->byte_us_q + t;
    return slot < s->slot_floor_us ? s->slot_floor_us : slot;
}

/* The baud in force and the slot's divisions by it, done here once. The
 * fraction is taken from below: r / 16 over baud / 16 + 1 (r << 12 would
 * overflow above 2^20 bit/s). */
static void prv_set_baud(km_servo_t *s, uint32_t baud)
{
    s->active_baud = baud;
    s->byte_us_q = baud ? 10000000u / baud : 0u;
    s->byte_us_r = baud ? 10000000u % baud : 0u;
    s->byte_us_f = ((s->byte_us_r >> 4) << 12) / ((baud >> 4) + 1u);
}

/* The answer's start after the frame: 0x12 alone, or the start of slot
 * `slot` (the own ID for the super ID, the list position for 0x82). Slot 0
 * needs no slot length (and no divide). */
static uint32_t prv_slot_delay_us(const km_servo_t *s, uint32_t slot, uint16_t max_answer_bytes)
{
    const uint32_t delay = km_regfile_get(&s->reg, KM_REG_RESPONSE_DELAY);
    return slot == 0u ? delay : delay + slot * prv_slot_us(s, max_answer_bytes);
}

uint32_t km_dispatch_delay_us(const km_servo_t *s, uint8_t frame_id, uint16_t max_answer_bytes)
{
    return prv_slot_delay_us(s, frame_id == KM_ID_SUPER ? km_servo_id(s) : 0u, max_answer_bytes);
}

void km_dispatch_answer_status(km_servo_t *s, uint8_t status, uint8_t frame_id, km_reply_t *reply)
{
    reply->len = km_encode_status(reply->bytes, km_servo_id(s), status);
    reply->delay_us = km_dispatch_delay_us(s, frame_id, 6u);
}

/* ---- init and accessors --------------------------------------------------- */

void km_servo_init(km_servo_t *s, const km_product_t *product, const uint32_t *persisted, uint32_t seed,
                   const km_servo_ops_t *ops)
{
    memset(s, 0, sizeof *s);
    km_regfile_init(&s->reg, product, persisted, seed);
    s->ops = ops;
    prv_set_baud(s, km_regfile_get(&s->reg, KM_REG_BAUD) * 100u);
}

uint32_t km_servo_active_baud(const km_servo_t *s)
{
    return s->active_baud;
}

uint8_t km_servo_status(const km_servo_t *s)
{
    return km_regfile_status(&s->reg);
}

uint32_t km_servo_reg(const km_servo_t *s, km_reg_index_t reg)
{
    return km_regfile_get(&s->reg, reg);
}

uint32_t km_servo_params_gen(const km_servo_t *s)
{
    return s->reg.gen;
}

void km_servo_note_checksum_error(km_servo_t *s)
{
    s->reg.unreported |= KM_ST_EXCEPTION;
}

void km_servo_set_live(km_servo_t *s, const km_live_t *live)
{
    km_regfile_set_live(&s->reg, live);
}

void km_servo_set_userdata_source(km_servo_t *s, uint8_t source)
{
    s->userdata_source = source;
    if (source == KM_USERDATA_UNAVAILABLE) {
        s->reg.hw_latched |= KM_HW_MEMORY; /* §5.2 0x35 bit 1: the store cannot be used */
    }
}

void km_servo_set_reset_cause(km_servo_t *s, uint8_t cause)
{
    s->reset_cause = cause;
}

void km_servo_set_active_baud(km_servo_t *s, uint32_t baud)
{
    prv_set_baud(s, baud);
}

void km_servo_set_slot_floor_us(km_servo_t *s, uint32_t us)
{
    s->slot_floor_us = us > KM_SLOT_FLOOR_MAX_US ? KM_SLOT_FLOOR_MAX_US : us;
}

/* ---- read 0x02 ------------------------------------------------------------- */

int km_dispatch_readable(uint8_t addr)
{
    const int r = km_reg_find(addr);
    return r >= 0 && (km_reg_table[r].access & KM_R) ? r : -1;
}

/* The longest answer a read of register r (-1: an error, the short
 * response) can give: what the slots are cut for, the same on every servo.
 * §5.3: a position answers i16 when it fits, else i32. */
static uint16_t prv_read_answer_max(int r)
{
    if (r < 0) {
        return 6u;
    }
    const km_layout_t layout = (km_layout_t)km_reg_table[r].layout;
    const uint8_t value = layout == KM_L_TEXT  ? TEXT_MAX
                          : layout == KM_L_POS ? 4u
                                               : km_reg_fixed_size(layout);
    return (uint16_t)(7u + value);
}

void km_dispatch_read_answer(km_servo_t *s, int r, uint8_t addr, uint32_t slot, km_reply_t *reply)
{
    uint8_t body[1 + TEXT_MAX];
    uint8_t n = 0u;
    if (r < 0) {
        km_regfile_exception(&s->reg);
    } else {
        body[0] = addr;
        n = km_reg_read(r)(s, (km_reg_index_t)r, &body[1]);
    }
    if (reply != NULL) {
        reply->len =
            r < 0 ? km_encode_status(reply->bytes, km_servo_id(s), km_regfile_own_status(&s->reg))
                  : km_encode_response(reply->bytes, km_servo_id(s), CMD_READ, body, (uint8_t)(1u + n));
        reply->delay_us = prv_slot_delay_us(s, slot, prv_read_answer_max(r));
    }
}

km_report_t km_cmd_read(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    /* "Malformed frames": a read carries exactly one address byte. */
    const bool one = f->body_len == 1;
    const int r = one ? km_dispatch_readable(f->body[0]) : -1;
    const uint32_t slot = f->id == KM_ID_SUPER ? km_servo_id(s) : 0u;
    /* At the broadcast ID run (a bad address is bit 5) but never answered. */
    const bool broadcast = f->id == KM_ID_BROADCAST;
    km_dispatch_read_answer(s, r, one ? f->body[0] : 0u, slot, broadcast ? NULL : reply);
    if (broadcast) {
        return KM_REPORT_NONE;
    }
    /* The status register's value is the ping's status byte. */
    return one && f->body[0] == 0x01 && !s->reg.flags ? KM_REPORT_ALL : KM_REPORT_OWN;
}

/* ---- ping 0x01 ----------------------------------------------------------------- */

km_report_t km_cmd_ping(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    if (f->body_len != 0) {
        km_regfile_exception(&s->reg);
    }
    if (f->id == KM_ID_BROADCAST) {
        return KM_REPORT_NONE;
    }
    km_dispatch_answer_status(s, km_regfile_status(&s->reg), f->id, reply);
    return KM_REPORT_ALL;
}

/* ---- write 0x03 and sync write 0x04 / 0x84 ------------------------------------- */

void km_dispatch_write(km_servo_t *s, uint8_t addr, const uint8_t *d, uint8_t len)
{
    const int r = km_reg_find(addr);
    if (r < 0) {
        km_regfile_exception(&s->reg); /* reserved address */
        return;
    }
    km_reg_write(r)(s, (km_reg_index_t)r, d, len); /* km_wr_none: read-only, bit 5 */
}

km_report_t km_cmd_write(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    const bool to_me = f->id == km_servo_id(s); /* before a write of 0x0F changes it */
    if (f->body_len < 1) {
        km_regfile_exception(&s->reg);
    } else {
        km_dispatch_write(s, f->body[0], &f->body[1], (uint8_t)(f->body_len - 1u));
    }
    /* §3: writes answer only at response level 1 and to our own ID; the
     * answer uses the ID the frame was sent to (the old one, §3). "Restart":
     * nothing after a restart answers. */
    if (!s->restarting && to_me && (km_regfile_get(&s->reg, KM_REG_CONFIG) & CONFIG_RESPONSE_LEVEL)) {
        const uint8_t old_id = f->id;
        reply->len = km_encode_status(reply->bytes, old_id, km_regfile_own_status(&s->reg));
        reply->delay_us = km_dispatch_delay_us(s, f->id, 6u);
        return KM_REPORT_OWN;
    }
    return KM_REPORT_NONE;
}

/* "Sync write": target ID only; the address is checked now, the value
 * when 0x84 runs it (motion rules depend on that moment). */
km_report_t km_cmd_sync_write(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    (void)reply;
    s->sync.full = false;
    if (f->id != km_servo_id(s) || f->body_len < 1) {
        km_regfile_exception(&s->reg);
        return KM_REPORT_NONE;
    }
    const int r = km_reg_find(f->body[0]);
    const uint8_t len = (uint8_t)(f->body_len - 1u);
    if (r < 0 || !(km_reg_table[r].access & KM_W)) {
        km_regfile_exception(&s->reg);
    } else if (len > sizeof s->sync.data) {
        km_regfile_fail(&s->reg);
    } else {
        s->sync.full = true;
        s->sync.addr = f->body[0];
        s->sync.len = len;
        memcpy(s->sync.data, &f->body[1], len);
    }
    return KM_REPORT_NONE;
}

/* §3: an empty buffer is nothing to do, not an error. */
km_report_t km_cmd_sync_execute(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    (void)reply;
    if (f->body_len != 0) {
        km_regfile_exception(&s->reg);
        s->sync.full = false;
    } else if (s->sync.full) {
        s->sync.full = false;
        km_dispatch_write(s, s->sync.addr, s->sync.data, s->sync.len);
    }
    return KM_REPORT_NONE;
}

/* ---- the frame's way through ------------------------------------------------------ */

/* The table's entry for `cmd`, or NULL: not a command of this firmware. */
static const prv_command_t *prv_command(uint8_t cmd)
{
#if KM_PROTOCOL_COMPACT
    for (const prv_command_t *c = s_commands; c != &s_commands[sizeof s_commands / sizeof s_commands[0]];
         c++) {
        if (c->cmd == cmd) {
            return c;
        }
    }
    return NULL;
#else
    const prv_command_t *c = &s_commands[PRV_SLOT_OF(cmd)];
    return c->cmd == cmd && c->run != NULL ? c : NULL;
#endif
}

/* The ID rules of the super and broadcast IDs (§3, "Super ID", "Multi-ID
 * write", "Multi-ID read 0x82"): false when the frame changes nothing here. */
static bool prv_admit(km_servo_t *s, const km_frame_view_t *f, uint8_t rules)
{
    const bool super = f->id == KM_ID_SUPER;
    const bool broadcast = f->id == KM_ID_BROADCAST;
    if (super && !(rules & RULE_SUPER)) {
        return false; /* a query address: other commands are ignored by every servo */
    }
    if ((rules & RULE_BROADCAST) && !broadcast) {
        /* to our own ID an exception; to the super ID, ignored (above) */
        s->reg.unreported |= KM_ST_EXCEPTION;
        s->sync.full = false;
        return false;
    }
    return true;
}

void km_servo_handle_view(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    reply->len = 0;
    reply->delay_us = 0;
    if (s->restarting) {
        return; /* "Restart": the servo is going down; nothing more runs */
    }
    if (f->id != km_servo_id(s) && f->id != KM_ID_SUPER && f->id != KM_ID_BROADCAST) {
        return; /* another servo's frame: it changes nothing here (§3 sync write) */
    }
    const prv_command_t *c = prv_command(f->cmd);
    const uint8_t rules = c != NULL ? c->rules : 0u;
    if (!prv_admit(s, f, rules)) {
        return;
    }
    if (!(rules & RULE_KEEPS_SYNC)) {
        s->sync.full = false; /* §3: any other command clears the 0x04 buffer */
    }
    s->reg.flags = 0u;
    km_report_t report = KM_REPORT_NONE;
    if (c != NULL) {
        report = c->run(s, f, reply);
    } else {
        km_regfile_exception(&s->reg); /* 0x7E and unknown commands: not supported */
    }
    /* "Status bits 5 and 6": an outcome is kept until a status answer has
     * carried it, then cleared, so it is never lost and never told twice. */
    if (report == KM_REPORT_ALL) {
        s->reg.unreported = 0u;
    } else if (report == KM_REPORT_NONE) {
        s->reg.unreported |= s->reg.flags;
    }
    s->reg.flags = 0u;
}

bool km_servo_may_answer(const km_servo_t *s, const km_frame_view_t *f)
{
    if (f->id == KM_ID_BROADCAST) {
        /* §3: the only command a listed servo answers at the broadcast ID */
        return KM_FEATURE_MULTI_READ && f->cmd == CMD_MULTI_READ;
    }
    return f->id == km_servo_id(s) || f->id == KM_ID_SUPER;
}

void km_servo_handle(km_servo_t *s, const km_frame_t *frame, km_reply_t *reply)
{
    const km_frame_view_t v = {
        .id = frame->id,
        .cmd = frame->cmd,
        .body_len = frame->body_len,
        .body = frame->body,
        .end_tick = frame->end_tick,
    };
    km_servo_handle_view(s, &v, reply);
}
