/* Dispatcher: one validated frame in, register changes, typed requests and
 * at most one answer out (PROTOCOL.md §3 commands, §4 status, §5 registers).
 * Where the spec is open, the choice is documented in
 * docs/protocol-decisions.md and named here by its heading. */
#include "km_servo.h"

#include <string.h>

#include "km_encoder.h"

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

static const uint8_t s_restart_magic[4] = {0xE1, 0xE2, 0xE3, 0xE4};

/* How an answer dealt with bits 5/6 ("Status bits 5 and 6"). */
typedef enum {
    PRV_UNANSWERED, /* no answer: this command's bits wait for a status answer */
    PRV_OWN,        /* the answer carried this command's bits (or had no status byte) */
    PRV_ALL,        /* the answer carried every unreported bit: they are cleared */
} prv_report_t;

/* ---- small helpers ---------------------------------------------------- */

static uint32_t prv_reg(const km_servo_t *s, km_reg_index_t r)
{
    return s->value[r];
}

static void prv_fail(km_servo_t *s)
{
    s->flags |= KM_ST_FAILED;
}

static void prv_exception(km_servo_t *s)
{
    s->flags |= KM_ST_EXCEPTION;
}

/* True when control accepted it (no control attached: accepted). */
static bool prv_request(km_servo_t *s, const km_request_t *req)
{
    if (s->ops && s->ops->request) {
        return s->ops->request(s->ops->ctx, req);
    }
    return true;
}

/* Every register change goes through here, so the change counter sees it. */
static void prv_set(km_servo_t *s, km_reg_index_t r, uint32_t v)
{
    s->value[r] = v;
    s->params_gen++;
}

static bool prv_commit(km_servo_t *s, const uint8_t *addrs, const uint32_t *values, uint8_t n)
{
    return s->ops && s->ops->commit && s->ops->commit(s->ops->ctx, addrs, values, n);
}

static uint8_t prv_next_random(km_servo_t *s)
{
    uint32_t x = s->prng; /* xorshift32: never 0 from a non-zero seed */
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    s->prng = x;
    return (uint8_t)x;
}

/* Runtime mirrors (§5.4): 0x5B/0x5C/0x5D follow 0x13/0x14/0x15 writes. */
static void prv_apply(km_servo_t *s, km_reg_index_t r, uint32_t v)
{
    prv_set(s, r, v);
    if (r == KM_REG_MAX_TORQUE) {
        s->value[KM_REG_TORQUE_LIMIT] = v;
    } else if (r == KM_REG_MAX_CURRENT) {
        s->value[KM_REG_CURRENT_LIMIT_NOW] = v;
    } else if (r == KM_REG_MAX_SPEED) {
        s->value[KM_REG_SPEED_LIMIT] = v;
    }
}

static int32_t prv_clamp16(int32_t v)
{
    return v > 32767 ? 32767 : (v < -32768 ? -32768 : v);
}

/* ---- status and timing ------------------------------------------------ */

/* Bits 7 and 4..0: the live and latched state, the same in every answer. */
static uint8_t prv_state_bits(const km_servo_t *s)
{
    uint8_t st = 0u;
    if (s->live.running) {
        st |= KM_ST_RUNNING;
    }
    if (s->hw_latched) {
        st |= KM_ST_HW_FAULT;
    }
    st |= (uint8_t)(s->live.protections & KM_ST_PROTECTION);
    return st;
}

/* "Status bits 5 and 6": what a ping (or a read of 0x01) reports: every
 * outcome no status answer has carried yet, and the current command's. */
uint8_t km_servo_status(const km_servo_t *s)
{
    return (uint8_t)(prv_state_bits(s) | s->unreported | s->flags);
}

/* What the answer to any other command reports: that command's own bits. */
static uint8_t prv_own_status(const km_servo_t *s)
{
    return (uint8_t)(prv_state_bits(s) | s->flags);
}

/* "Super-ID answer slots": servo i starts response_delay + i * slot after
 * the frame, slot = the longest answer this read can give on the wire at
 * the active baud plus a guard of 2 byte times, rounded up to 1 us; at
 * least the board's slot floor ("Answer slots on emulated buses"). */
static uint32_t prv_slot_us(const km_servo_t *s, uint16_t answer_bytes)
{
    const uint32_t bits = (uint32_t)(answer_bytes + 2u) * 10u;
    const uint32_t slot = (bits * 1000000u + s->active_baud - 1u) / s->active_baud;
    return slot < s->slot_floor_us ? s->slot_floor_us : slot;
}

/* The answer's start after the frame: 0x12 alone, or the start of slot
 * `slot` (the own ID for the super ID, the list position for 0x82). */
static uint32_t prv_slot_delay_us(const km_servo_t *s, uint32_t slot, uint16_t max_answer_bytes)
{
    return prv_reg(s, KM_REG_RESPONSE_DELAY) + slot * prv_slot_us(s, max_answer_bytes);
}

static uint32_t prv_delay_us(const km_servo_t *s, uint8_t frame_id, uint16_t max_answer_bytes)
{
    return prv_slot_delay_us(s, frame_id == KM_ID_SUPER ? km_servo_id(s) : 0u, max_answer_bytes);
}

static void prv_answer_status(km_servo_t *s, uint8_t status, uint8_t frame_id, km_reply_t *reply)
{
    reply->len = km_encode_status(reply->bytes, km_servo_id(s), status);
    reply->delay_us = prv_delay_us(s, frame_id, 6u);
}

/* ---- init and accessors ----------------------------------------------- */

/* "Limits that contradict each other": a minimum angle limit at or above
 * the maximum would leave no target reachable. 0 = no limit (§5.1). */
static bool prv_angle_limits_ok(int16_t lo, int16_t hi)
{
    return lo == 0 || hi == 0 || lo < hi;
}

/* A stored value passes the checks a write of it would: right bytes, in
 * range, cross-field rules. Anything else (a baud of 0 from a damaged or
 * older store) is replaced by the default rather than run with. */
static bool prv_persisted_ok(km_reg_index_t r, const km_product_t *p, uint32_t v)
{
    uint8_t b[4];
    uint32_t packed;
    const uint8_t n = km_reg_fixed_size((km_layout_t)km_reg_table[r].layout);
    if (n == 0u || n > 3u) {
        return false;
    }
    km_put_le(b, v, n);
    return km_reg_validate(r, p, b, n, &packed) && packed == v;
}

void km_servo_init(km_servo_t *s, const km_product_t *product, const uint32_t *persisted,
                   uint32_t seed, const km_servo_ops_t *ops)
{
    memset(s, 0, sizeof *s);
    s->product = product;
    s->ops = ops;
    unsigned k = 0;
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        uint32_t v = km_reg_default((km_reg_index_t)i, product);
        if (km_reg_table[i].persisted && persisted &&
            prv_persisted_ok((km_reg_index_t)i, product, persisted[k])) {
            v = persisted[k];
        }
        k += km_reg_table[i].persisted;
        prv_apply(s, (km_reg_index_t)i, v);
    }
    /* §5.4: 0x5B..0x5D start equal to the stored 0x13..0x15. They come later
     * in the table than their sources, so the loop above set them to the
     * product defaults after the mirror had been applied: apply it again. */
    prv_apply(s, KM_REG_MAX_TORQUE, s->value[KM_REG_MAX_TORQUE]);
    prv_apply(s, KM_REG_MAX_CURRENT, s->value[KM_REG_MAX_CURRENT]);
    prv_apply(s, KM_REG_MAX_SPEED, s->value[KM_REG_MAX_SPEED]);
    /* "Limits that contradict each other" apply to stored values too. */
    if (!prv_angle_limits_ok((int16_t)prv_reg(s, KM_REG_ANGLE_MIN), (int16_t)prv_reg(s, KM_REG_ANGLE_MAX))) {
        s->value[KM_REG_ANGLE_MIN] = km_reg_default(KM_REG_ANGLE_MIN, product);
        s->value[KM_REG_ANGLE_MAX] = km_reg_default(KM_REG_ANGLE_MAX, product);
    }
    s->active_baud = prv_reg(s, KM_REG_BAUD) * 100u;
    s->prng = seed ? seed : 0x2545F491u;
}

uint8_t km_servo_id(const km_servo_t *s)
{
    return (uint8_t)prv_reg(s, KM_REG_ID);
}

uint32_t km_servo_active_baud(const km_servo_t *s)
{
    return s->active_baud;
}

uint32_t km_servo_reg(const km_servo_t *s, km_reg_index_t reg)
{
    return s->value[reg];
}

void km_servo_note_checksum_error(km_servo_t *s)
{
    s->unreported |= KM_ST_EXCEPTION;
}

void km_servo_set_live(km_servo_t *s, const km_live_t *live)
{
    s->live = *live;
    s->hw_latched |= live->hw_faults; /* §5.2 0x35: latched until restart */
    if (live->torque_forced && prv_reg(s, KM_REG_TORQUE_SWITCH) != live->torque_switch) {
        prv_set(s, KM_REG_TORQUE_SWITCH, live->torque_switch); /* §5.4 0x64 = 5: set by the servo */
    }
}

uint32_t km_servo_params_gen(const km_servo_t *s)
{
    return s->params_gen;
}

static const km_control_gains_t s_default_gains = KM_CONTROL_GAINS_DEFAULT;

void km_servo_control_params(const km_servo_t *s, km_control_params_t *out)
{
    const uint8_t config = (uint8_t)prv_reg(s, KM_REG_CONFIG);
    const uint32_t volt = prv_reg(s, KM_REG_VOLTAGE_LIMITS);
    const uint32_t temp = prv_reg(s, KM_REG_TEMP_LIMITS);
    const uint32_t cur = prv_reg(s, KM_REG_CURRENT_LIMIT);
    const uint32_t stall = prv_reg(s, KM_REG_STALL_LIMIT);
    memset(out, 0, sizeof *out);
    out->variant = s->product->variant;
    out->reverse = (config & 0x04u) != 0u;
    out->idle_brake = (config & 0x02u) != 0u;
    out->power_on_brake = (config & 0x01u) != 0u;
    out->zero_offset1 = (int16_t)prv_reg(s, KM_REG_ZERO_OFFSET1);
    out->zero_offset2 = (int16_t)prv_reg(s, KM_REG_ZERO_OFFSET2);
    out->max_torque = (uint16_t)prv_reg(s, KM_REG_MAX_TORQUE);
    out->max_current_ma = (uint16_t)prv_reg(s, KM_REG_MAX_CURRENT);
    out->max_speed_dps = (uint16_t)prv_reg(s, KM_REG_MAX_SPEED);
    out->angle_min = (int16_t)prv_reg(s, KM_REG_ANGLE_MIN);
    out->angle_max = (int16_t)prv_reg(s, KM_REG_ANGLE_MAX);
    out->travel_min = s->product->travel_min;
    out->travel_max = s->product->travel_max;
    out->pos_read_min = s->product->pos_read_min;
    out->pos_read_max = s->product->pos_read_max;
    out->prot_enable = (uint8_t)prv_reg(s, KM_REG_PROT_ENABLE);
    out->prot_release = (uint8_t)prv_reg(s, KM_REG_PROT_RELEASE);
    out->prot_state = (uint8_t)prv_reg(s, KM_REG_PROT_STATE);
    out->voltage_high_v = (uint8_t)volt;
    out->voltage_low_v = (uint8_t)(volt >> 8);
    out->temp_trip_c = (uint8_t)temp;
    out->temp_hysteresis_c = (uint8_t)(temp >> 8);
    out->current_trip_ma = (uint16_t)cur;
    out->current_time_100ms = (uint8_t)(cur >> 16);
    out->stall_pwm = (uint16_t)stall;
    out->stall_time_100ms = (uint8_t)(stall >> 16);
    out->control_mode = (uint8_t)prv_reg(s, KM_REG_CONTROL_MODE);
    out->torque_limit = (uint16_t)prv_reg(s, KM_REG_TORQUE_LIMIT);
    out->current_limit_ma = (uint16_t)prv_reg(s, KM_REG_CURRENT_LIMIT_NOW);
    out->speed_limit_dps = (uint16_t)prv_reg(s, KM_REG_SPEED_LIMIT);
    out->torque_switch = (uint8_t)prv_reg(s, KM_REG_TORQUE_SWITCH);
    out->gains = s->product->gains ? *s->product->gains : s_default_gains;
}

void km_servo_set_userdata_source(km_servo_t *s, uint8_t source)
{
    s->userdata_source = source;
    if (source == KM_USERDATA_UNAVAILABLE) {
        s->hw_latched |= KM_HW_MEMORY; /* §5.2 0x35 bit 1: the store cannot be used */
    }
}

void km_servo_set_reset_cause(km_servo_t *s, uint8_t cause)
{
    s->reset_cause = cause;
}

void km_servo_set_active_baud(km_servo_t *s, uint32_t baud)
{
    s->active_baud = baud;
}

void km_servo_set_slot_floor_us(km_servo_t *s, uint32_t us)
{
    s->slot_floor_us = us > KM_SLOT_FLOOR_MAX_US ? KM_SLOT_FLOOR_MAX_US : us;
}

/* ---- read ------------------------------------------------------------- */

static uint8_t prv_put_pos(uint8_t *out, int32_t v)
{
    /* §5.3: i16 when it fits, else i32; the length tells the master. */
    if (v >= -32768 && v <= 32767) {
        return km_put_le(out, (uint32_t)v, 2);
    }
    return km_put_le(out, (uint32_t)v, 4);
}

/* Longest value a register can answer with (for the super-ID slot). */
static uint8_t prv_max_value_size(km_layout_t layout)
{
    switch (layout) {
    case KM_L_TEXT:
        return TEXT_MAX;
    case KM_L_POS:
        return 4;
    default:
        return km_reg_fixed_size(layout);
    }
}

/* Encodes register r's current value; returns its byte count. */
static uint8_t prv_encode_value(km_servo_t *s, km_reg_index_t r, uint8_t *out)
{
    const km_layout_t layout = (km_layout_t)km_reg_table[r].layout;
    switch (r) {
    case KM_REG_STATUS:
        out[0] = km_servo_status(s);
        out[1] = prv_next_random(s);
        return 2;
    case KM_REG_PRODUCT_INFO: {
        uint8_t n = 0;
        const char *m = s->product->model;
        while (m && m[n] && n < TEXT_MAX) {
            out[n] = (uint8_t)m[n];
            n++;
        }
        return n;
    }
    case KM_REG_PROTOCOL_VERSION:
    case KM_REG_FIRMWARE_VERSION:
        return km_put_le(out, km_reg_default(r, s->product), 4);
    case KM_REG_HW_FAULTS:
        out[0] = s->hw_latched;
        return 1;
    case KM_REG_PROT_FLAGS:
        out[0] = (uint8_t)(s->live.protections & KM_ST_PROTECTION);
        return 1;
    case KM_REG_POSITION:
        return prv_put_pos(out, s->live.position);
    case KM_REG_DEVIATION:
        return prv_put_pos(out, s->live.deviation);
    case KM_REG_SPEED:
        return km_put_le(out, (uint32_t)prv_clamp16(s->live.speed), 2);
    case KM_REG_CURRENT:
        return km_put_le(out, (uint32_t)prv_clamp16(s->live.current), 2);
    case KM_REG_PWM:
        return km_put_le(out, (uint32_t)prv_clamp16(s->live.pwm), 2);
    case KM_REG_TEMPERATURE:
        return km_put_le(out, (uint32_t)prv_clamp16(s->live.temperature), 2);
    case KM_REG_VOLTAGE:
        return km_put_le(out, (uint32_t)prv_clamp16(s->live.voltage), 2);
    case KM_REG_ROTATION_TIME:
        return km_put_le(out, s->live.rotation_ms, 4);
    default:
        return km_put_le(out, s->value[r], km_reg_fixed_size(layout));
    }
}

/* The readable register at `addr`, or -1 (unknown, or write-only). */
static int prv_readable(uint8_t addr)
{
    const int r = km_reg_find(addr);
    return r >= 0 && (km_reg_table[r].access & KM_R) ? r : -1;
}

/* The longest answer a read of register r (-1: an error, the short
 * response) can give: what the slots are cut for, the same on every servo. */
static uint16_t prv_read_answer_max(int r)
{
    if (r < 0) {
        return 6u;
    }
    return (uint16_t)(7u + prv_max_value_size((km_layout_t)km_reg_table[r].layout));
}

/* The answer to a read of register r (-1: bit 5 and the short response),
 * started in slot `slot`. */
static void prv_read_answer(km_servo_t *s, int r, uint8_t addr, uint32_t slot, km_reply_t *reply)
{
    const uint32_t delay = prv_slot_delay_us(s, slot, prv_read_answer_max(r));
    if (r < 0) {
        prv_exception(s);
        reply->len = km_encode_status(reply->bytes, km_servo_id(s), prv_own_status(s));
        reply->delay_us = delay;
        return;
    }
    uint8_t body[1 + TEXT_MAX];
    body[0] = addr;
    const uint8_t n = prv_encode_value(s, (km_reg_index_t)r, &body[1]);
    reply->len = km_encode_response(reply->bytes, km_servo_id(s), CMD_READ, body, (uint8_t)(1u + n));
    reply->delay_us = delay;
}

static void prv_read(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    /* "Malformed frames": a read carries exactly one address byte. */
    const int r = f->body_len == 1 ? prv_readable(f->body[0]) : -1;
    const uint32_t slot = f->id == KM_ID_SUPER ? km_servo_id(s) : 0u;
    prv_read_answer(s, r, f->body_len == 1 ? f->body[0] : 0u, slot, reply);
}

/* ---- write ------------------------------------------------------------ */

static void prv_commit_one(km_servo_t *s, km_reg_index_t r, uint32_t v)
{
    const uint8_t addr = km_reg_table[r].addr;
    if (!prv_commit(s, &addr, &v, 1)) {
        prv_fail(s); /* the store failed: the old value stays in force */
        return;
    }
    prv_apply(s, r, v);
}

/* A default packed as km_reg_default() packs it (the wire bytes of a
 * fixed layout shorter than 4). Always inlined: with a constant layout it
 * folds to a mask or nothing. */
static inline __attribute__((always_inline)) uint32_t prv_pack_default(uint32_t v,
                                                                       km_layout_t layout)
{
    const uint8_t size = km_reg_fixed_size_const(layout);
    return size > 0u && size < 4u ? v & ((1u << (8u * size)) - 1u) : v;
}

/* The registers a user-data reset writes back and their defaults, straight
 * from the register table at compile time (no loop over the 47 registers,
 * no look-up, no switch per register): persisted and writable from the bus.
 * "User-data reset": factory data (persisted, not writable from the bus:
 * the level-1 zero offset 0x16) is per-unit calibration that no master
 * could write back, so no level resets it; §5.1 0x03 level 1 keeps ID,
 * baud and both zero offsets. Returns how many. */
static uint8_t prv_reset_list(const km_product_t *p, uint8_t level, uint8_t *regs, uint8_t *addrs,
                              uint32_t *values)
{
    uint8_t n = 0;
    const bool keep_ids = level == 1;
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi)                              \
    if ((persisted) && ((access) & KM_W) &&                                                     \
        !(keep_ids && (KM_REG_##ident == KM_REG_ID || KM_REG_##ident == KM_REG_BAUD ||          \
                       KM_REG_##ident == KM_REG_ZERO_OFFSET2))) {                               \
        regs[n] = (uint8_t)KM_REG_##ident;                                                      \
        addrs[n] = (addr);                                                                      \
        values[n] = prv_pack_default((uint32_t)(def), (layout));                                \
        n++;                                                                                    \
    }
#include "km_registers.def"
#undef KM_REG
    return n;
}

static void prv_userdata_reset(km_servo_t *s, uint8_t level)
{
    /* The register indexes are kept beside the addresses, so applying the
     * committed values needs no look-up by address. */
    uint8_t regs[KM_REG_PERSISTED_COUNT];
    uint8_t addrs[KM_REG_PERSISTED_COUNT];
    uint32_t values[KM_REG_PERSISTED_COUNT];
    const uint8_t n = prv_reset_list(s->product, level, regs, addrs, values);
    if (!prv_commit(s, addrs, values, n)) {
        prv_fail(s);
        return;
    }
    for (uint8_t j = 0; j < n; j++) {
        prv_apply(s, (km_reg_index_t)regs[j], values[j]);
    }
}

/* Servo-mode rotation (0x65..0x68): "Motion preconditions". */
static bool prv_servo_motion_allowed(km_servo_t *s)
{
    const uint32_t ts = prv_reg(s, KM_REG_TORQUE_SWITCH);
    return !s->hw_latched && prv_reg(s, KM_REG_CONTROL_MODE) != KM_MODE_MOTOR_ONLY &&
           (ts == KM_TORQUE_ON || ts == KM_TORQUE_ARMED);
}

/* Motor mode (0x6E..0x70): "Motion preconditions"; a request for less
 * motion is taken with a fault latched ("Protections"). */
static bool prv_motor_motion_allowed(km_servo_t *s, const km_request_t *req)
{
    return (!s->hw_latched || km_request_less_motion(req)) && prv_reg(s, KM_REG_CONTROL_MODE) != KM_MODE_SERVO_ONLY;
}

static bool prv_is_encoder(const km_servo_t *s)
{
    return s->product->variant == KM_VARIANT_ENCODER;
}

/* The move a servo-mode rotation register asks for (0x65..0x68), decoded
 * from its bytes; false for bytes it does not take. */
static bool prv_decode_move(km_reg_index_t r, const uint8_t *d, uint8_t len, km_move_t *mv)
{
    mv->relative = false;
    mv->time_or_speed = 0u; /* omitted = fastest */
    mv->pwm_cap = 1000u;
    switch (r) {
    case KM_REG_MOVE_TIME:
    case KM_REG_MOVE_SPEED:
        if (len != 2 && len != 4) {
            return false;
        }
        mv->kind = r == KM_REG_MOVE_TIME ? KM_MOVE_TIME : KM_MOVE_SPEED;
        mv->target = (int16_t)km_get_le(d, 2);
        if (len == 4) {
            mv->time_or_speed = (uint16_t)km_get_le(d + 2, 2);
        }
        return true;
    case KM_REG_INTERPOLATE:
        if (len != 2) {
            return false;
        }
        mv->kind = KM_MOVE_STREAM;
        mv->target = (int16_t)km_get_le(d, 2);
        return true;
    default: { /* KM_REG_SERVO_ADVANCED: control byte, p1, p2 */
        if (len != 5) {
            return false;
        }
        const uint8_t hi = (uint8_t)(d[0] >> 4), lo = (uint8_t)(d[0] & 0x0Fu);
        const uint16_t p2 = (uint16_t)km_get_le(d + 3, 2);
        mv->relative = hi == 1u;
        mv->target = (int16_t)km_get_le(d + 1, 2);
        /* low nibble: 0 p2 = time ms, 1 p2 = speed deg/s, 2 p2 = PWM cap at the fastest speed */
        mv->kind = lo == 0u ? KM_MOVE_TIME : KM_MOVE_SPEED;
        mv->time_or_speed = lo == 2u ? 0u : p2;
        mv->pwm_cap = lo == 2u ? p2 : 1000u;
        return hi <= 1u && lo <= 2u && mv->pwm_cap <= 1000u;
    }
    }
}

static void prv_servo_motion(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    km_request_t req;
    req.kind = KM_REQ_MOVE;
    if (!prv_decode_move(r, d, len, &req.u.move) || !prv_servo_motion_allowed(s)) {
        prv_fail(s);
        return;
    }
    if (!prv_request(s, &req)) {
        prv_fail(s); /* control refused it: nothing moves, 0x64 stays */
        return;
    }
    if (prv_reg(s, KM_REG_TORQUE_SWITCH) == KM_TORQUE_ARMED) {
        prv_set(s, KM_REG_TORQUE_SWITCH, KM_TORQUE_ON); /* §5.4 0x64 = 3: on at the next rotation */
    }
}

/* 0x70's control byte and parameters as a run; false for bytes it does
 * not take (bit 6 set, a p2 kind above 1, a PWM above 1000, or what only
 * an encoder product can do on another). */
static bool prv_decode_motor_advanced(const km_servo_t *s, const uint8_t *d, uint8_t len, km_motor_run_t *run)
{
    if (len != 5) {
        return false;
    }
    const uint8_t c = d[0];
    const uint8_t p1_kind = (uint8_t)((c >> 4) & 3u), p2_kind = (uint8_t)((c >> 2) & 3u);
    run->mode = (c & 0x80u) ? KM_RUN_STOP : (p2_kind == 1u ? KM_RUN_SPEED : KM_RUN_PWM);
    run->reverse = (c & 0x01u) != 0u;
    run->value = (uint16_t)km_get_le(d + 3, 2);
    run->until = p1_kind; /* 0 none, 1 time, 2 angle, 3 turns */
    run->amount = (uint16_t)km_get_le(d + 1, 2);
    run->after = (c & 0x02u) ? KM_AFTER_BRAKE : KM_AFTER_FREE;
    const bool encoder_only = p1_kind >= 2u || p2_kind == 1u;
    return !(c & 0x40u) && p2_kind <= 1u && !(p2_kind == 0u && run->value > 1000u) &&
           !(encoder_only && !prv_is_encoder(s));
}

/* 0x6E (PWM) or 0x6F (speed, encoder products): a signed value, run on. */
static bool prv_decode_motor(const km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len,
                             km_motor_run_t *run)
{
    uint32_t packed;
    if (!km_reg_validate(r, s->product, d, len, &packed) || (r == KM_REG_MOTOR_SPEED && !prv_is_encoder(s))) {
        return false;
    }
    const int16_t v = (int16_t)packed;
    run->mode = r == KM_REG_MOTOR_TORQUE ? KM_RUN_PWM : KM_RUN_SPEED;
    run->reverse = v < 0;
    run->value = (uint16_t)(v < 0 ? -(int32_t)v : (int32_t)v);
    run->until = KM_UNTIL_NONE;
    run->amount = 0u;
    run->after = KM_AFTER_IDLE; /* a stop by 0 leaves the idle output */
    return true;
}

static void prv_motor_motion(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    km_request_t req;
    req.kind = KM_REQ_MOTOR;
    const bool ok = r == KM_REG_MOTOR_ADVANCED ? prv_decode_motor_advanced(s, d, len, &req.u.run)
                                               : prv_decode_motor(s, r, d, len, &req.u.run);
    if (!ok || !prv_motor_motion_allowed(s, &req) || !prv_request(s, &req)) {
        prv_fail(s);
        return;
    }
}

/* "Zeroing": 0x46 written and 0x18 = 0 on encoder products both make the
 * current position zero, and both are refused (bit 6) while a hardware
 * fault is latched: the position sensor may be the fault, and a zero taken
 * from it would survive the restart that clears the fault. */
static void prv_zero_position(km_servo_t *s)
{
    if (s->hw_latched) {
        prv_fail(s);
        return;
    }
    const km_request_t req = {.kind = KM_REQ_ZERO_POSITION};
    if (!prv_request(s, &req)) {
        prv_fail(s);
    }
}

/* "Limits that contradict each other": a runtime limit (0x5B..0x5D) above
 * its maximum (0x13..0x15), or angle limits with min >= max, are refused
 * with bit 6 so control can rely on min < max and runtime <= maximum. */
static bool prv_consistent(const km_servo_t *s, km_reg_index_t r, uint32_t v)
{
    switch (r) {
    case KM_REG_TORQUE_LIMIT:
        return v <= prv_reg(s, KM_REG_MAX_TORQUE);
    case KM_REG_CURRENT_LIMIT_NOW:
        return v <= prv_reg(s, KM_REG_MAX_CURRENT);
    case KM_REG_SPEED_LIMIT:
        return v <= prv_reg(s, KM_REG_MAX_SPEED);
    case KM_REG_ANGLE_MIN:
        return prv_angle_limits_ok((int16_t)v, (int16_t)prv_reg(s, KM_REG_ANGLE_MAX));
    case KM_REG_ANGLE_MAX:
        return prv_angle_limits_ok((int16_t)prv_reg(s, KM_REG_ANGLE_MIN), (int16_t)v);
    default:
        return true;
    }
}

/* Executes a write of `len` bytes to `addr` (0x03, 0x84, an 0x83 entry).
 * Returns false when no answer may follow (a restart). */
static bool prv_write(km_servo_t *s, uint8_t addr, const uint8_t *d, uint8_t len)
{
    const int ri = km_reg_find(addr);
    if (ri < 0 || !(km_reg_table[ri].access & KM_W)) {
        prv_exception(s); /* reserved address, or read-only (0x16 included) */
        return true;
    }
    const km_reg_index_t r = (km_reg_index_t)ri;
    uint32_t v = 0;
    km_request_t req = {0};
    switch (r) {
    case KM_REG_RESTART:
        if (len == 4 && memcmp(d, s_restart_magic, 4) == 0) {
            /* "Restart": at once; nothing after this frame may run. */
            s->restarting = true;
            if (s->ops && s->ops->restart) {
                s->ops->restart(s->ops->ctx);
            }
            return false;
        }
        prv_fail(s);
        return true;
    case KM_REG_USERDATA_RESET:
        if (!km_reg_validate(r, s->product, d, len, &v)) {
            prv_fail(s);
        } else {
            prv_userdata_reset(s, (uint8_t)v);
        }
        return true;
    case KM_REG_ZERO_INCREMENT: {
        if (!km_reg_validate(r, s->product, d, len, &v)) {
            prv_fail(s);
            return true;
        }
        const int8_t inc = (int8_t)v;
        if (inc == 0 && prv_is_encoder(s)) { /* §5.1 0x18: 0 zeroes an encoder */
            prv_zero_position(s);
            return true;
        }
        const int32_t next = (int16_t)prv_reg(s, KM_REG_ZERO_OFFSET2) + inc;
        if (next < -s->product->zero_offset2_max || next > s->product->zero_offset2_max) {
            prv_fail(s);
            return true;
        }
        prv_commit_one(s, KM_REG_ZERO_OFFSET2, (uint32_t)(uint16_t)(int16_t)next);
        return true;
    }
    case KM_REG_POSITION:
        /* §5.3 0x46: any value zeroes it, on motor (encoder) products. */
        if ((len != 2 && len != 4) || !prv_is_encoder(s)) {
            prv_fail(s);
            return true;
        }
        prv_zero_position(s);
        return true;
    case KM_REG_PROT_FLAGS:
        if (!km_reg_validate(r, s->product, d, len, &v)) {
            prv_fail(s);
            return true;
        }
        req.kind = KM_REQ_PROTECTION_CLEAR;
        req.u.clear = (uint8_t)v;
        if (!prv_request(s, &req)) {
            prv_fail(s); /* §5.2 0x36: a protection whose cause still holds stays */
        } else {
        }
        return true;
    case KM_REG_TORQUE_SWITCH:
        if (!km_reg_validate(r, s->product, d, len, &v) || (v == 2u && s->hw_latched)) {
            prv_fail(s); /* 4, 5 and up are not writable; no holding with a fault */
            return true;
        }
        req.kind = KM_REQ_TORQUE;
        req.u.torque = (uint8_t)v;
        if (!prv_request(s, &req)) {
            prv_fail(s); /* control refused (e.g. a protection latched): 0x64 stays */
            return true;
        }
        prv_set(s, r, v);
        return true;
    case KM_REG_CONTROL_MODE:
        /* §5.4 0x5A: motor-only only when idle or with torque off. */
        if (!km_reg_validate(r, s->product, d, len, &v) ||
            (v == 2u && s->live.running && prv_reg(s, KM_REG_TORQUE_SWITCH) == 2u)) {
            prv_fail(s);
            return true;
        }
        prv_set(s, r, v);
        return true;
    case KM_REG_MOVE_TIME:
    case KM_REG_MOVE_SPEED:
    case KM_REG_SERVO_ADVANCED:
    case KM_REG_INTERPOLATE:
        prv_servo_motion(s, r, d, len);
        return true;
    case KM_REG_MOTOR_TORQUE:
    case KM_REG_MOTOR_SPEED:
    case KM_REG_MOTOR_ADVANCED:
        prv_motor_motion(s, r, d, len);
        return true;
    default:
        if (!km_reg_validate(r, s->product, d, len, &v) || !prv_consistent(s, r, v)) {
            prv_fail(s);
        } else if (km_reg_table[r].persisted) {
            prv_commit_one(s, r, v); /* ID and baud too: committed before they apply */
        } else {
            prv_set(s, r, v);
        }
        return true;
    }
}

/* ---- multi-ID write 0x83 ---------------------------------------------- */

/* §3: only these addresses may be multi-written. */
static bool prv_multi_addr_ok(uint8_t addr)
{
    return addr == 0x64 || addr == 0x65 || addr == 0x66 || addr == 0x68 || addr == 0x6E || addr == 0x6F;
}

/* The parameter sizes each allowed address takes. */
static bool prv_multi_k_ok(uint8_t addr, uint8_t k)
{
    switch (addr) {
    case 0x64:
        return k == 1;
    case 0x65:
    case 0x66:
        return k == 2 || k == 4;
    default: /* 0x68, 0x6E, 0x6F */
        return k == 2;
    }
}

/* "Multi-ID write": every servo on the bus judges the frame. */
static void prv_multi_write(km_servo_t *s, const km_frame_view_t *f)
{
    if (f->body_len < 1u || !prv_multi_addr_ok(f->body[0])) {
        /* §4: an address the command does not support is bit 5, on every
         * servo (each saw the broken command); nothing runs. */
        prv_exception(s);
        s->sync.full = false;
        return;
    }
    const uint8_t n_params = f->body_len >= 2u ? (uint8_t)(f->body_len - 2u) : 0u;
    const uint8_t k = f->body_len >= 2u ? f->body[1] : 0u;
    if (!prv_multi_k_ok(f->body[0], k) || n_params == 0u || n_params % (k + 1u) != 0u) {
        prv_fail(s); /* the right address with malformed entries: a bad value */
        s->sync.full = false;
        return;
    }
    /* The scan over up to 49 entries: the ID, the body and its end in
     * locals (the loop's stores could alias them otherwise). */
    const uint8_t own = km_servo_id(s);
    const uint8_t *const body = f->body;
    const uint8_t len = f->body_len;
    const uint8_t step = (uint8_t)(k + 1u);
    for (uint8_t off = 2; off < len; off = (uint8_t)(off + step)) {
        if (body[off] == own) {
            s->sync.full = false;
            (void)prv_write(s, body[0], &body[off + 1u], k);
            return;
        }
    }
    /* Not in the list: this servo does nothing at all. */
}

/* ---- multi-ID read 0x82 ------------------------------------------------ */

/* "Multi-ID read 0x82": F9 FF FE len 82 addr id_0 .. id_n-1 cs. Every servo
 * judges the frame; a listed servo answers exactly what a 0x02 read of addr
 * answers, starting in slot j, j = its first position in the list. */
static prv_report_t prv_multi_read(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    if (f->body_len < 2u) {
        /* No address, or no ID: a malformed frame, bit 5 on every servo
         * (nobody can answer it); nothing else happens. */
        prv_exception(s);
        s->sync.full = false;
        return PRV_UNANSWERED;
    }
    const uint8_t addr = f->body[0];
    const int r = prv_readable(addr);
    /* The scan over up to 249 IDs: the ID, the body and its end in locals
     * (the loop's stores could alias them otherwise). */
    const uint8_t own = km_servo_id(s);
    const uint8_t *const ids = &f->body[1];
    const uint8_t n = (uint8_t)(f->body_len - 1u);
    const uint8_t *const end = ids + n;
    const uint8_t *const end4 = ids + (n & ~3u); /* the whole groups of four */
    const uint8_t *p = ids;
    /* Four IDs a pass, then the rest: the scan is what a long list costs
     * (tools/bench-m0); the answer is due j slots later anyway. */
    while (p != end4 && p[0] != own && p[1] != own && p[2] != own && p[3] != own) {
        p += 4;
    }
    while (p != end && *p != own) {
        p++;
    }
    if (p == end) {
        if (r < 0) {
            /* §4: an address the read does not support is bit 5 on every
             * servo, as for 0x83; unlisted servos report it at a ping. */
            prv_exception(s);
            s->sync.full = false;
        }
        return PRV_UNANSWERED; /* not listed: nothing else changes */
    }
    s->sync.full = false; /* a command to this servo (§3) */
    prv_read_answer(s, r, addr, (uint32_t)(p - ids), reply);
    /* As a read: the status register's value is the ping's status byte. */
    return addr == 0x01 && !s->flags ? PRV_ALL : PRV_OWN;
}

/* ---- extension command 0x7F --------------------------------------------- */

/* "Extension command 0x7F": a read in this firmware's own address space;
 * what the dispatcher does not keep (the fault log) the firmware answers
 * (ops->ext_read). Returns false for an address nobody has (bit 5, like a
 * read). */
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

/* The value size an address always answers with (at least 2): what the
 * super-ID slots are cut for, the same on every servo of the bus. */
static uint16_t prv_ext_size(uint8_t n)
{
    return n > 2u ? n : 2u;
}

static void prv_ext_read(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    uint8_t body[1 + KM_EXT_VALUE_MAX];
    uint8_t n = 0;
    if (f->body_len != 1 || !prv_ext_value(s, f->body[0], &body[1], &n)) {
        prv_exception(s);
        prv_answer_status(s, prv_own_status(s), f->id, reply);
        return;
    }
    body[0] = f->body[0];
    reply->len = km_encode_response(reply->bytes, km_servo_id(s), KM_CMD_EXT, body, (uint8_t)(1u + n));
    reply->delay_us = prv_delay_us(s, f->id, (uint16_t)(7u + prv_ext_size(n)));
}

/* ---- firmware update 0x78 (docs/update.md) ---------------------------- */

/* The application's side of 0x78 is the firmware's (ops->update): ENTER
 * restarts into the bootloader, STATUS answers state 0, anything else is
 * bit 5 with the short response. A firmware without the op treats 0x78 as
 * any command it does not have (bit 5, no answer). Answered to our own ID
 * only, at the normal response delay. */
static bool prv_update(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply, bool to_me)
{
    uint8_t body[KM_UPDATE_ANSWER_MAX];
    uint8_t n = 0u;
    if (s->ops->update == NULL) {
        prv_exception(s); /* like any command this firmware does not have */
        return false;
    }
    if (!s->ops->update(s->ops->ctx, f->body, f->body_len, body, &n)) {
        prv_exception(s);
        if (to_me) {
            prv_answer_status(s, prv_own_status(s), f->id, reply);
            return true;
        }
        return false;
    }
    if (f->body_len >= 1u && f->body[0] == KM_UPDATE_SUB_ENTER) {
        s->restarting = true; /* an accepted ENTER is a restart: nothing after it runs */
        return false;
    }
    if (!to_me || n == 0u) {
        return false;
    }
    reply->len = km_encode_response(reply->bytes, km_servo_id(s), KM_CMD_UPDATE_FW, body, n);
    reply->delay_us = prv_delay_us(s, f->id, (uint16_t)(6u + n));
    return true;
}

/* ---- dispatch --------------------------------------------------------- */

/* Runs one command addressed to this servo; fills *reply. */
static prv_report_t prv_dispatch(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    const bool to_me = f->id == km_servo_id(s);
    const bool broadcast = f->id == KM_ID_BROADCAST;
    switch (f->cmd) {
    case CMD_PING:
        if (f->body_len != 0) {
            prv_exception(s);
        }
        if (broadcast) {
            return PRV_UNANSWERED;
        }
        prv_answer_status(s, km_servo_status(s), f->id, reply);
        return PRV_ALL;
    case CMD_READ:
        prv_read(s, f, reply);
        if (broadcast) {
            reply->len = 0; /* run, so a bad address is bit 5; never answered */
            return PRV_UNANSWERED;
        }
        /* The status register's value is the ping's status byte. */
        return f->body_len == 1 && f->body[0] == 0x01 && !s->flags ? PRV_ALL : PRV_OWN;
    case KM_CMD_EXT:
        prv_ext_read(s, f, reply);
        if (broadcast) {
            reply->len = 0;
            return PRV_UNANSWERED;
        }
        return PRV_OWN;
    case CMD_WRITE: {
        bool may_answer = true;
        if (f->body_len < 1) {
            prv_exception(s);
        } else {
            may_answer = prv_write(s, f->body[0], &f->body[1], (uint8_t)(f->body_len - 1u));
        }
        /* §3: writes answer only at response level 1 and to our own ID; the
         * answer uses the ID the frame was sent to (the old one, §3). */
        if (may_answer && to_me && (prv_reg(s, KM_REG_CONFIG) & CONFIG_RESPONSE_LEVEL)) {
            const uint8_t old_id = f->id;
            reply->len = km_encode_status(reply->bytes, old_id, prv_own_status(s));
            reply->delay_us = prv_delay_us(s, f->id, 6u);
            return PRV_OWN;
        }
        return PRV_UNANSWERED;
    }
    case CMD_SYNC_WRITE:
        /* "Sync write": target ID only; the address is checked now, the
         * value when 0x84 runs it (motion rules depend on that moment). */
        s->sync.full = false;
        if (!to_me || f->body_len < 1) {
            prv_exception(s);
            return PRV_UNANSWERED;
        }
        {
            const int r = km_reg_find(f->body[0]);
            const uint8_t len = (uint8_t)(f->body_len - 1u);
            if (r < 0 || !(km_reg_table[r].access & KM_W)) {
                prv_exception(s);
            } else if (len > sizeof s->sync.data) {
                prv_fail(s);
            } else {
                s->sync.full = true;
                s->sync.addr = f->body[0];
                s->sync.len = len;
                memcpy(s->sync.data, &f->body[1], len);
            }
        }
        return PRV_UNANSWERED;
    case CMD_SYNC_EXECUTE:
        if (f->body_len != 0) {
            prv_exception(s);
            s->sync.full = false;
        } else if (s->sync.full) {
            s->sync.full = false;
            (void)prv_write(s, s->sync.addr, s->sync.data, s->sync.len);
        }
        return PRV_UNANSWERED; /* an empty buffer is nothing to do, not an error (§3) */
    case KM_CMD_UPDATE_FW:
        return prv_update(s, f, reply, to_me) ? PRV_OWN : PRV_UNANSWERED;
    default:
        /* 0x7E and unknown commands: not supported. */
        prv_exception(s);
        return PRV_UNANSWERED;
    }
}

void km_servo_handle_view(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    reply->len = 0;
    reply->delay_us = 0;
    if (s->restarting) {
        return; /* "Restart": the servo is going down; nothing more runs */
    }
    const uint8_t own = km_servo_id(s);
    const bool super = f->id == KM_ID_SUPER;
    const bool broadcast = f->id == KM_ID_BROADCAST;
    if (f->id != own && !super && !broadcast) {
        return; /* another servo's frame: it changes nothing here (§3 sync write) */
    }
    /* "Super ID": a query address; commands other than ping, read and the
     * extension read sent to it are ignored by every servo. */
    if (super && f->cmd != CMD_PING && f->cmd != CMD_READ && f->cmd != KM_CMD_EXT) {
        return;
    }
    /* "Multi-ID write" and "Multi-ID read 0x82": broadcast only. To our own
     * ID it is an exception; to the super ID, ignored (above). */
    const bool multi = f->cmd == CMD_MULTI_WRITE || f->cmd == CMD_MULTI_READ;
    if (multi && !broadcast) {
        s->unreported |= KM_ST_EXCEPTION;
        s->sync.full = false;
        return;
    }
    if (f->cmd != CMD_SYNC_WRITE && f->cmd != CMD_SYNC_EXECUTE && !multi) {
        s->sync.full = false; /* §3: any other command clears the 0x04 buffer */
    }
    s->flags = 0u;
    prv_report_t report;
    if (f->cmd == CMD_MULTI_WRITE) {
        prv_multi_write(s, f);
        report = PRV_UNANSWERED;
    } else if (f->cmd == CMD_MULTI_READ) {
        report = prv_multi_read(s, f, reply);
    } else {
        report = prv_dispatch(s, f, reply);
    }
    /* "Status bits 5 and 6": an outcome is kept until a status answer has
     * carried it, then cleared, so it is never lost and never told twice. */
    if (report == PRV_ALL) {
        s->unreported = 0u;
    } else if (report == PRV_UNANSWERED) {
        s->unreported |= s->flags;
    }
    s->flags = 0u;
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
