/* The servo as the bus sees it: the register file, the status byte, the
 * sync-write buffer, and the dispatcher that turns a validated frame into
 * changes, typed requests to the rest of the firmware, and an answer
 * (PROTOCOL.md §3, §4, §5). Pure logic: no hardware, no heap. Decisions
 * where the spec is open are in docs/protocol-decisions.md. */
#ifndef KM_SERVO_H
#define KM_SERVO_H

#include <stdbool.h>
#include <stdint.h>

#include "km_frame.h"
#include "km_product.h"
#include "km_registers.h"
#include "km_live.h"
#include "km_params.h"
#include "km_request.h"
#include "km_status.h"

/* What the firmware provides: narrow, typed, no hardware types. */
typedef struct {
    /* Commit persisted registers all-or-nothing; true once durable. On
     * false the old values stay in force and status bit 6 is set. */
    bool (*commit)(void *ctx, const uint8_t *addrs, const uint32_t *values, uint8_t n);
    /* 0x02 with the exact magic: restart now, no answer. */
    void (*restart)(void *ctx);
    /* Motion and protection requests; `req` is valid during the call only.
     * Returns false when control refuses it (a motion the variant cannot do,
     * a protection latched): the dispatcher then sets status bit 6 and
     * changes nothing. */
    bool (*request)(void *ctx, const km_request_t *req);
    /* 0x78 firmware update, the application's side (docs/update.md §4):
     * the frame's body in; `answer` (KM_UPDATE_ANSWER_MAX bytes) gets the
     * answer's body, *answer_len its length (0: none). False: not served
     * here (status bit 5). NULL: 0x78 is not supported at all. */
    bool (*update)(void *ctx, const uint8_t *body, uint8_t n, uint8_t *answer, uint8_t *answer_len);
    /* 0x7F of an extension register the firmware keeps (the fault log,
     * KM_EXT_FAULT_*): its value into `out` (KM_EXT_VALUE_MAX bytes), *n
     * its length, always the same for an address. False: no such register
     * (bit 5). NULL: none. */
    bool (*ext_read)(void *ctx, uint8_t addr, uint8_t *out, uint8_t *n);
    void *ctx;
} km_servo_ops_t;

/* The answer to send: `len` 0 = none. Starts `delay_us` after the frame's
 * last byte. */
typedef struct {
    uint8_t bytes[KM_FRAME_MAX];
    uint16_t len;
    uint32_t delay_us;
} km_reply_t;

typedef struct {
    const km_product_t *product;
    const km_servo_ops_t *ops;
    uint32_t value[KM_REG_COUNT]; /* register file, wire bytes packed LE */
    uint32_t active_baud;         /* bps in force until restart (0x10 applies then) */
    uint32_t prng;                /* xorshift32 state for the 0x01 random byte */
    uint32_t slot_floor_us;       /* least answer slot (emulated boards; 0 = the rule) */
    km_live_t live;
    uint8_t flags;                /* bits 5/6 of the command being handled */
    uint8_t unreported;           /* bits 5/6 no status answer has carried yet */
    bool restarting;              /* a restart was requested: nothing more runs */
    uint8_t hw_latched;           /* 0x35, latched until restart */
    uint8_t userdata_source;      /* KM_USERDATA_*, extension register 0x01 */
    uint8_t reset_cause;          /* km_reset_cause_t of this boot, extension 0x02 */
    uint32_t params_gen;          /* bumped on every applied register change */
    struct {
        bool full;
        uint8_t addr;
        uint8_t len;
        uint8_t data[8];
    } sync;                       /* 0x04 buffer */
} km_servo_t;

/* Persisted values by register address, in table order of the P registers;
 * `persisted` may be NULL (product defaults). */
void km_servo_init(km_servo_t *s, const km_product_t *product, const uint32_t *persisted,
                   uint32_t seed, const km_servo_ops_t *ops);

/* Processes one validated frame; fills *reply (len 0 = no answer). */
void km_servo_handle(km_servo_t *s, const km_frame_t *frame, km_reply_t *reply);

/* The same for a frame the parser handed out as a view (its body where it
 * lies: no copy). */
void km_servo_handle_view(km_servo_t *s, const km_frame_view_t *frame, km_reply_t *reply);

/* The parser saw a bad-checksum frame with our ID: bit 5 until a status
 * answer reports it ("Status bits 5 and 6"). */
void km_servo_note_checksum_error(km_servo_t *s);

/* Control's live state, every tick: the live registers, status bits 7
 * and 0..3, 0x35's latch (until restart); 0x64 shows live->torque_switch
 * whenever control set it by itself (live->torque_forced: 5 while a
 * protection acts, §5.4, and what it returned to after). */
void km_servo_set_live(km_servo_t *s, const km_live_t *live);

/* The control registers decoded into engineering units (km_params.h). */
void km_servo_control_params(const km_servo_t *s, km_control_params_t *out);

/* Changes every time a register value changes (a write, a commit, a reset,
 * 0x64 turned on by a rotation command): decode the params again only then. */
uint32_t km_servo_params_gen(const km_servo_t *s);

/* This firmware's extension registers, read with command 0x7F ("customer
 * custom", PROTOCOL.md §7) so they stay out of the vendor's register map:
 * `F9 FF id 03 7F addr cs` answers `F9 F5 id len 7F addr value cs`.
 * docs/protocol-decisions.md "Extension command 0x7F" has the frames. */
#define KM_CMD_EXT 0x7Fu
#define KM_CMD_UPDATE_FW 0x78u   /* docs/update.md */
#define KM_UPDATE_ANSWER_MAX 80u
#define KM_UPDATE_SUB_ENTER 0x01u  /* accepted by ops->update: the firmware restarts */
#define KM_EXT_USERDATA_SOURCE 0x01u /* u8 KM_USERDATA_*: where the user data came from */
#define KM_EXT_RESET_CAUSE 0x02u     /* u8 km_reset_cause_t (hal/km_hal_system.h) */
#define KM_EXT_ACTIVE_BAUD 0x03u     /* u16 baud / 100 in force (0x10 may differ) */
#define KM_EXT_FAULT_SUMMARY 0x10u   /* 7 B: u32 events ever, u8 held, u8 kept from before the reset, u8 16 */
#define KM_EXT_FAULT_ENTRY 0x11u     /* 0x11 + n, n = 0 (newest) .. 15: 18 B, firmware/app/km_fault_log.h */
#define KM_EXT_FAULT_ENTRIES 16u
#define KM_EXT_VALUE_MAX 18u         /* the longest extension value */

/* Extension 0x01: where the user data in force came from at boot. The
 * values follow the store's mount results. */
#define KM_USERDATA_LOADED 0u           /* from flash, as committed */
#define KM_USERDATA_MIGRATED 1u         /* from flash; registers new to this firmware at defaults */
#define KM_USERDATA_DEFAULTS_BLANK 2u   /* product defaults: flash erased (first boot) */
#define KM_USERDATA_DEFAULTS_INVALID 3u /* product defaults: no valid record in flash */
#define KM_USERDATA_DEFAULTS_SCHEMA 4u  /* product defaults: stored layout from another version */
#define KM_USERDATA_UNAVAILABLE 5u      /* store unusable: defaults, commits fail (bit 6) */
void km_servo_set_userdata_source(km_servo_t *s, uint8_t source);

/* Extension 0x02: why the MCU last reset (the hal's km_reset_cause_t). */
void km_servo_set_reset_cause(km_servo_t *s, uint8_t cause);

/* The bus runs at another baud than 0x10 asks (the board cannot make it):
 * the super-ID slots and extension 0x03 follow the baud in force. */
void km_servo_set_active_baud(km_servo_t *s, uint32_t baud);

/* docs/protocol-decisions.md "Answer slots on emulated buses": the super-ID
 * and 0x82 slots are at least `us` (an emulated board's km_app_set_bus_floors();
 * 0 on real boards: the slot rule alone). Capped at KM_SLOT_FLOOR_MAX_US, so the
 * last slot (250 x floor) still fits the 32-bit delay. */
#define KM_SLOT_FLOOR_MAX_US 1000000u
void km_servo_set_slot_floor_us(km_servo_t *s, uint32_t us);

uint8_t km_servo_id(const km_servo_t *s);
uint32_t km_servo_active_baud(const km_servo_t *s);
uint8_t km_servo_status(const km_servo_t *s);

/* Stored register value (packed wire bytes), for control and the store. */
uint32_t km_servo_reg(const km_servo_t *s, km_reg_index_t reg);

#endif
