/* SPDX-License-Identifier: Apache-2.0 */
/* The servo as the bus sees it (docs/protocol.md §3, §4, §5): a validated frame in, register changes and
 * typed requests, at most one answer out (docs/architecture.md "The data path"). */
#ifndef KM_SERVO_H
#define KM_SERVO_H

#include <stdbool.h>
#include <stdint.h>

#include "km_ext.h"
#include "km_frame.h"
#include "km_live.h"
#include "km_params.h"
#include "km_product.h"
#include "km_regfile.h"
#include "km_registers.h"
#include "km_request.h"
#include "km_status.h"

/* What the firmware provides: narrow, typed, no hardware types. */
typedef struct {
    /* Commit persisted registers all-or-nothing; true once durable. On
     * false the old values stay in force and status bit 6 is set. */
    bool (*commit)(void *ctx, const uint8_t *addrs, const uint32_t *values, uint8_t n);
    /* 0x02 with the exact magic: restart now, no answer. */
    void (*restart)(void *ctx);
    /* Motion and protection requests; false: control refuses (status bit 6, nothing changed). */
    bool (*request)(void *ctx, const km_request_t *req);
    /* 0x78 firmware update, the application's side (docs/update.md §4); false: bit 5; NULL: unsupported. */
    bool (*update)(void *ctx, const uint8_t *body, uint8_t n, uint8_t *answer, uint8_t *answer_len);
    /* 0x7F of an extension register the firmware keeps (the fault log); false: bit 5; NULL: none. */
    bool (*ext_read)(void *ctx, uint8_t addr, uint8_t *out, uint8_t *n);
    void *ctx;
} km_servo_ops_t;

/* The answer to send: `len` 0 = none. Starts `delay_us` after the frame's
 * last byte. Both before the bytes: a short load's offset from the reply's
 * address (docs/footprint.md "Register values from one base"). */
typedef struct {
    uint32_t delay_us;
    uint16_t len;
    uint8_t bytes[KM_FRAME_MAX];
} km_reply_t;

typedef struct km_servo {
    const km_servo_ops_t *ops;
    bool restarting;        /* a restart was requested: nothing more runs */
    km_regfile_t reg;       /* values, status bits, control's report */
    uint32_t active_baud;   /* bps in force until restart (0x10 applies then) */
    uint32_t slot_floor_us; /* least answer slot (emulated boards; 0 = the rule) */
    /* 1e7 / active_baud (the microseconds of 10 bits x 1e6) as quotient,
     * remainder, and the remainder over the baud << 12, floored: an answer
     * slot without a division (km_servo.c prv_slot_us) */
    uint32_t byte_us_q;
    uint32_t byte_us_r;
    uint32_t byte_us_f;
    uint8_t userdata_source; /* KM_USERDATA_*, extension register 0x01 */
    uint8_t reset_cause;     /* km_reset_cause_t of this boot, extension 0x02 */
    struct {
        bool full;
        uint8_t addr;
        uint8_t len;
        uint8_t data[8];
    } sync; /* 0x04 buffer */
} km_servo_t;

/* Persisted values by register address, in table order of the P registers;
 * `persisted` may be NULL (product defaults). */
void km_servo_init(km_servo_t *s, const km_product_t *product, const uint32_t *persisted, uint32_t seed,
                   const km_servo_ops_t *ops);

/* Processes one validated frame; fills *reply (len 0 = no answer). */
void km_servo_handle(km_servo_t *s, const km_frame_t *frame, km_reply_t *reply);

/* The same for a frame the parser handed out as a view (its body where it
 * lies: no copy). reply->bytes are written only for an answer (reply->len
 * > 0 on return): a frame without one leaves them as they were, so the
 * caller may keep there an answer still to be sent (firmware/app: one
 * buffer for the answer built and the answer on the wire). */
void km_servo_handle_view(km_servo_t *s, const km_frame_view_t *frame, km_reply_t *reply);

/* The multi-ID read 0x82 (this firmware's definition, docs/protocol-decisions.md
 * "Multi-ID read 0x82") is compiled in (1, the default) or out (0: the 32 KiB
 * STM32G031F6 build, where 0x82 is an unsupported command, docs/footprint.md
 * "What gives way"). */
#ifndef KM_FEATURE_MULTI_READ
#define KM_FEATURE_MULTI_READ 1
#endif

/* False when `frame` cannot be answered by this servo (another servo's ID;
 * the broadcast ID, except 0x82): handling it leaves reply->bytes alone. */
bool km_servo_may_answer(const km_servo_t *s, const km_frame_view_t *frame);

/* The parser saw a bad-checksum frame with our ID: bit 5 until a status
 * answer reports it ("Status bits 5 and 6"). */
void km_servo_note_checksum_error(km_servo_t *s);

/* Control's live state, every tick: the live registers, status bits 7 and 0..3, 0x35's latch, 0x64 (§5.4). */
void km_servo_set_live(km_servo_t *s, const km_live_t *live);

/* The control registers decoded into engineering units (km_params.h). */
void km_servo_control_params(const km_servo_t *s, km_control_params_t *out);

/* Changes every time a register value changes (a write, a commit, a reset,
 * 0x64 turned on by a rotation command): decode the params again only then. */
uint32_t km_servo_params_gen(const km_servo_t *s);

/* 0x78 firmware update (docs/update.md), the application's side. */
#define KM_CMD_UPDATE_FW 0x78u
#define KM_UPDATE_ANSWER_MAX 80u
#define KM_UPDATE_SUB_ENTER 0x01u /* accepted by ops->update: the firmware restarts */

/* Extension 0x01: where the user data in force came from at boot
 * (KM_USERDATA_*, km_ext.h); KM_USERDATA_UNAVAILABLE also latches 0x35
 * bit 1 (memory). */
void km_servo_set_userdata_source(km_servo_t *s, uint8_t source);

/* Extension 0x02: why the MCU last reset (the hal's km_reset_cause_t). */
void km_servo_set_reset_cause(km_servo_t *s, uint8_t cause);

/* The bus runs at another baud than 0x10 asks (the board cannot make it):
 * the super-ID slots and extension 0x03 follow the baud in force. */
void km_servo_set_active_baud(km_servo_t *s, uint32_t baud);

/* Slot floor of the super-ID and 0x82 answers, capped at KM_SLOT_FLOOR_MAX_US (docs/protocol-decisions.md
 * "Answer slots on emulated buses"). */
#define KM_SLOT_FLOOR_MAX_US 1000000u
void km_servo_set_slot_floor_us(km_servo_t *s, uint32_t us);

/* 0x0F, the ID in force (a write applies it at once; its answer uses the old one). */
static inline uint8_t km_servo_id(const km_servo_t *s)
{
    return (uint8_t)km_regfile_get(&s->reg, KM_REG_ID);
}

uint32_t km_servo_active_baud(const km_servo_t *s);
uint8_t km_servo_status(const km_servo_t *s);

/* Stored register value (packed wire bytes), for control and the store. */
uint32_t km_servo_reg(const km_servo_t *s, km_reg_index_t reg);

#endif
