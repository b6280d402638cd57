/* SPDX-License-Identifier: Apache-2.0 */
/* Read hooks of the registers whose value is computed, not kept: the
 * status (0x01), the model name (0x0A), the latched hardware faults
 * (0x35), the active protections (0x36) and control's live values
 * (0x46..0x4D, §5.3). */
#include "km_hooks.h"

#include <stddef.h>
#include <string.h>

#include "km_servo.h"

#define TEXT_MAX 16u

static int32_t prv_clamp16(int32_t v)
{
    return v > 32767 ? 32767 : (v < -32768 ? -32768 : v);
}

/* §5.1 0x01: [status][random]; the random byte lets a master spot two
 * servos with the same ID. */
uint8_t km_rd_status(km_servo_t *s, km_reg_index_t r, uint8_t *out)
{
    (void)r;
    out[0] = km_regfile_status(&s->reg);
    out[1] = km_regfile_random(&s->reg);
    return 2;
}

/* 0x0A: the model name, ASCII, up to 16 bytes. */
uint8_t km_rd_text(km_servo_t *s, km_reg_index_t r, uint8_t *out)
{
    (void)r;
    uint8_t n = 0;
    const char *m = s->reg.product->model;
    while (m && m[n] && n < TEXT_MAX) {
        out[n] = (uint8_t)m[n];
        n++;
    }
    return n;
}

/* 0x35: latched until restart. */
uint8_t km_rd_hw_faults(km_servo_t *s, km_reg_index_t r, uint8_t *out)
{
    (void)r;
    out[0] = s->reg.hw_latched;
    return 1;
}

/* 0x36: the protections acting now (a write clears, km_wr_prot_clear). */
uint8_t km_rd_protections(km_servo_t *s, km_reg_index_t r, uint8_t *out)
{
    (void)r;
    out[0] = (uint8_t)(s->reg.live.protections & KM_ST_PROTECTION);
    return 1;
}

/* 0x46, 0x4C: i16 when the value fits, else i32; the length tells the
 * master (§5.3). */
uint8_t km_rd_live_pos(km_servo_t *s, km_reg_index_t r, uint8_t *out)
{
    const int32_t v = r == KM_REG_POSITION ? s->reg.live.position : s->reg.live.deviation;
    return km_put_le(out, (uint32_t)v, v >= -32768 && v <= 32767 ? 2u : 4u);
}

/* 0x47..0x4B are speed, current, PWM, temperature, voltage: consecutive rows and consecutive
 * int32 fields of km_live_t, so a register's field is one offset from the first. */
_Static_assert(KM_REG_CURRENT == KM_REG_SPEED + 1 && KM_REG_PWM == KM_REG_SPEED + 2 &&
                   KM_REG_TEMPERATURE == KM_REG_SPEED + 3 && KM_REG_VOLTAGE == KM_REG_SPEED + 4,
               "km_registers.def: 0x47..0x4B out of order");
_Static_assert(offsetof(km_live_t, current) == offsetof(km_live_t, speed) + 4u &&
                   offsetof(km_live_t, pwm) == offsetof(km_live_t, speed) + 8u &&
                   offsetof(km_live_t, temperature) == offsetof(km_live_t, speed) + 12u &&
                   offsetof(km_live_t, voltage) == offsetof(km_live_t, speed) + 16u,
               "km_live_t: speed..voltage not consecutive int32 fields");

/* 0x47..0x4B: speed, current, PWM, temperature, voltage as i16, clamped. */
uint8_t km_rd_live16(km_servo_t *s, km_reg_index_t r, uint8_t *out)
{
    int32_t v;
    const uint8_t *const first = (const uint8_t *)&s->reg.live + offsetof(km_live_t, speed);
    memcpy(&v, first + sizeof v * (size_t)(r - KM_REG_SPEED), sizeof v);
    return km_put_le(out, (uint32_t)prv_clamp16(v), 2);
}

/* 0x4D: ms since the last rotation command, u32. */
uint8_t km_rd_rotation_time(km_servo_t *s, km_reg_index_t r, uint8_t *out)
{
    (void)r;
    return km_put_le(out, s->reg.live.rotation_ms, 4);
}
