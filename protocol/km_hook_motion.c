/* SPDX-License-Identifier: Apache-2.0 */
/* Write hooks of the rotation registers (§5.4): 0x64, the moves 0x65..0x68, the runs 0x6E..0x70, decoded into
 * include/km/km_request.h. */
#include <stddef.h>

#include "km_hooks.h"

#include "km_servo.h"

/* 0x64's request as three words: a zeroed 12-byte local is a call of newlib's byte-loop memset under -Os
 * (65 instructions on the M0, in every 0x83 of 0x64; docs/footprint.md "f6whole"). */
static km_request_t prv_torque_request(uint8_t torque)
{
    _Static_assert(sizeof(km_request_t) == 12u && offsetof(km_request_t, u.torque) == 2u,
                   "kind in byte 0, torque in 2");
    _Static_assert(KM_REQ_TORQUE == 0 && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "word 0 is torque << 16");
    union {
        uint32_t words[3];
        km_request_t req;
    } r;
    r.words[0] = (uint32_t)torque << 16;
    r.words[1] = 0u;
    r.words[2] = 0u;
    return r.req;
}

/* 0x64: 0..3 are torque requests (4, 5 and up are not writable); on (2) is
 * refused with a hardware fault latched. The register takes the value once
 * control accepts it. */
void km_wr_torque_switch(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    uint32_t v;
    if (!km_reg_validate(r, s->reg.product, d, len, &v) || (v == KM_TORQUE_ON && s->reg.hw_latched)) {
        km_regfile_fail(&s->reg);
        return;
    }
    const km_request_t req = prv_torque_request((uint8_t)v);
    if (!km_hook_request(s, &req)) {
        km_regfile_fail(&s->reg); /* control refused (e.g. a protection latched): 0x64 stays */
        return;
    }
    km_regfile_set(&s->reg, r, v);
}

/* A decoded servo-mode move: "Motion preconditions" (no fault latched, not
 * motor-only, 0x64 on or armed), then control; §5.4 0x64 = 3 turns on
 * (2) at the rotation control accepts. */
static void prv_servo_move(km_servo_t *s, const km_request_t *req)
{
    const uint32_t ts = km_regfile_get(&s->reg, KM_REG_TORQUE_SWITCH);
    if (s->reg.hw_latched || km_regfile_get(&s->reg, KM_REG_CONTROL_MODE) == KM_MODE_MOTOR_ONLY ||
        (ts != KM_TORQUE_ON && ts != KM_TORQUE_ARMED) || !km_hook_request(s, req)) {
        km_regfile_fail(&s->reg); /* nothing moves, 0x64 stays */
        return;
    }
    if (ts == KM_TORQUE_ARMED) {
        km_regfile_set(&s->reg, KM_REG_TORQUE_SWITCH, KM_TORQUE_ON);
    }
}

/* 0x65 (in time), 0x66 (at speed): i16 target [, u16 time ms or speed
 * deg/s; omitted = fastest]. 0x68: i16 target of a stream. */
void km_wr_move(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    const bool stream = r == KM_REG_INTERPOLATE;
    if (stream ? len != 2 : (len != 2 && len != 4)) {
        km_regfile_fail(&s->reg);
        return;
    }
    km_request_t req;
    req.kind = KM_REQ_MOVE;
    req.u.move.kind = stream ? KM_MOVE_STREAM : r == KM_REG_MOVE_TIME ? KM_MOVE_TIME : KM_MOVE_SPEED;
    req.u.move.relative = false;
    req.u.move.target = (int16_t)km_get_le(d, 2);
    req.u.move.time_or_speed = len == 4 ? (uint16_t)km_get_le(d + 2, 2) : 0u;
    req.u.move.pwm_cap = 1000u;
    prv_servo_move(s, &req);
}

/* 0x67: control byte, i16 p1, i16 p2. High nibble 0 = p1 is the target, 1
 * = p1 adds to the target in force; low nibble 0 = p2 is a time in ms,
 * 1 = a speed in deg/s, 2 = a PWM cap 0..1000 at the fastest speed. */
void km_wr_servo_advanced(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    (void)r;
    const uint8_t c = len == 5 ? d[0] : 0xFFu; /* a wrong length fails as a bad control byte does */
    const uint8_t hi = (uint8_t)(c >> 4), lo = (uint8_t)(c & 0x0Fu);
    if (hi > 1u || lo > 2u) {
        km_regfile_fail(&s->reg);
        return;
    }
    const uint16_t p2 = (uint16_t)km_get_le(d + 3, 2);
    km_request_t req;
    req.kind = KM_REQ_MOVE;
    req.u.move.kind = lo == 0u ? KM_MOVE_TIME : KM_MOVE_SPEED;
    req.u.move.relative = hi == 1u;
    req.u.move.target = (int16_t)km_get_le(d + 1, 2);
    req.u.move.time_or_speed = lo == 2u ? 0u : p2;
    req.u.move.pwm_cap = lo == 2u ? p2 : 1000u;
    if (req.u.move.pwm_cap > 1000u) {
        km_regfile_fail(&s->reg);
        return;
    }
    prv_servo_move(s, &req);
}

#if KM_FEATURE_MOTOR_MODE
/* An encoder product (§6): the one with speed runs and counted angles or turns. */
static bool prv_is_encoder(const km_servo_t *s)
{
    return km_product_variant(s->reg.product) == KM_VARIANT_ENCODER;
}

/* A decoded motor run: "Motion preconditions" (no fault latched, but a
 * request for less motion is taken with one: "Protections"; not
 * servo-only), then control. */
static void prv_motor_run(km_servo_t *s, const km_request_t *req)
{
    if ((s->reg.hw_latched && !km_request_less_motion(req)) ||
        km_regfile_get(&s->reg, KM_REG_CONTROL_MODE) == KM_MODE_SERVO_ONLY || !km_hook_request(s, req)) {
        km_regfile_fail(&s->reg);
    }
}

/* 0x6E: PWM -1000..1000, 0x6F: deg/s (encoder products): the sign is the
 * direction, 0 stops with the idle output. */
void km_wr_motor(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    uint32_t packed;
    if (!km_reg_validate(r, s->reg.product, d, len, &packed) ||
        (r == KM_REG_MOTOR_SPEED && !prv_is_encoder(s))) {
        km_regfile_fail(&s->reg);
        return;
    }
    const int16_t v = (int16_t)packed;
    km_request_t req;
    req.kind = KM_REQ_MOTOR;
    req.u.run.mode = r == KM_REG_MOTOR_TORQUE ? KM_RUN_PWM : KM_RUN_SPEED;
    req.u.run.reverse = v < 0;
    req.u.run.value = (uint16_t)(v < 0 ? -(int32_t)v : (int32_t)v);
    req.u.run.until = KM_UNTIL_NONE;
    req.u.run.amount = 0u;
    req.u.run.after = KM_AFTER_IDLE;
    prv_motor_run(s, &req);
}

/* 0x70: control byte, u16 p1, u16 p2. Bit 7 stops now; bit 6 must be 0;
 * bits 5:4 p1 = 0 run on, 1 time (0.1 s), 2 angle (deg), 3 turns (0.1
 * turn); bits 3:2 p2 = 0 PWM 0..1000, 1 speed deg/s; bit 1 after stop 0
 * free, 1 brake; bit 0 reverse. Angle, turns and speed: encoder products
 * only ("Encoder-only commands"). */
void km_wr_motor_advanced(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    (void)r;
    const uint8_t c = len == 5 ? d[0] : 0x40u; /* a wrong length fails as bit 6 set does */
    const uint8_t p1_kind = (uint8_t)((c >> 4) & 3u), p2_kind = (uint8_t)((c >> 2) & 3u);
    const bool encoder_only = p1_kind >= 2u || p2_kind == 1u;
    if ((c & 0x40u) || p2_kind > 1u || (encoder_only && !prv_is_encoder(s))) {
        km_regfile_fail(&s->reg);
        return;
    }
    km_request_t req;
    req.kind = KM_REQ_MOTOR;
    req.u.run.mode = (c & 0x80u) ? KM_RUN_STOP : (p2_kind == 1u ? KM_RUN_SPEED : KM_RUN_PWM);
    req.u.run.reverse = (c & 0x01u) != 0u;
    req.u.run.value = (uint16_t)km_get_le(d + 3, 2);
    req.u.run.until = p1_kind;
    req.u.run.amount = (uint16_t)km_get_le(d + 1, 2);
    req.u.run.after = (c & 0x02u) ? KM_AFTER_BRAKE : KM_AFTER_FREE;
    if (p2_kind == 0u && req.u.run.value > 1000u) {
        km_regfile_fail(&s->reg);
        return;
    }
    prv_motor_run(s, &req);
}
#else
/* Without motor mode (KM_FEATURE_MOTOR_MODE=0) only 0x6F reaches this
 * hook (0x6E and 0x70 are KM_GONE): an encoder product's command, it fails
 * with bit 6 as it does on a potentiometer product (§6). */
void km_wr_motor(km_servo_t *s, km_reg_index_t r, const uint8_t *d, uint8_t len)
{
    (void)r;
    (void)d;
    (void)len;
    km_regfile_fail(&s->reg);
}
#endif
