/* SPDX-License-Identifier: Apache-2.0 */
/* The control registers decoded into engineering units for control
 * (include/km/km_params.h): the one place their wire forms (0x11 bits,
 * the two-field limits 0x3C..0x3F) are taken apart. */
#include "km_servo.h"

#define CONFIG_DIRECTION 0x04u      /* 0x11 bit 2: counter-clockwise positive */
#define CONFIG_IDLE_BRAKE 0x02u     /* 0x11 bit 1 */
#define CONFIG_POWER_ON_BRAKE 0x01u /* 0x11 bit 0 */

/* A register's value by its offset from 0x11's: every one read below within a load's 124-byte reach. */
#define PRV_AT(reg) ((reg)-KM_REG_CONFIG)
_Static_assert(KM_REG_CONFIG <= KM_REG_ZERO_OFFSET1 && KM_REG_TORQUE_SWITCH - KM_REG_CONFIG <= 31,
               "km_registers.def: the control registers beyond a load's reach of 0x11");

static const km_control_gains_t s_default_gains = KM_CONTROL_GAINS_DEFAULT;

void km_servo_control_params(const km_servo_t *s, km_control_params_t *out)
{
    const km_regfile_t *rf = &s->reg;
    /* The values from one base register, 0x11's: each register a short load's offset from it, not an address
     * of its own (docs/footprint.md "Register values from one base"). */
    const uint32_t *value = &rf->value[KM_REG_CONFIG];
    __asm__("" : "+r"(value));
    const uint8_t config = (uint8_t)value[PRV_AT(KM_REG_CONFIG)];
    const uint32_t volt = value[PRV_AT(KM_REG_VOLTAGE_LIMITS)];
    const uint32_t temp = value[PRV_AT(KM_REG_TEMP_LIMITS)];
    const uint32_t cur = value[PRV_AT(KM_REG_CURRENT_LIMIT)];
    const uint32_t stall = value[PRV_AT(KM_REG_STALL_LIMIT)];
    out->variant = km_product_variant(rf->product);
    out->reverse = (config & CONFIG_DIRECTION) != 0u;
    out->idle_brake = (config & CONFIG_IDLE_BRAKE) != 0u;
    out->power_on_brake = (config & CONFIG_POWER_ON_BRAKE) != 0u;
    out->zero_offset1 = (int16_t)value[PRV_AT(KM_REG_ZERO_OFFSET1)];
    out->zero_offset2 = (int16_t)value[PRV_AT(KM_REG_ZERO_OFFSET2)];
    out->max_torque = (uint16_t)value[PRV_AT(KM_REG_MAX_TORQUE)];
    out->max_current_ma = (uint16_t)value[PRV_AT(KM_REG_MAX_CURRENT)];
    out->max_speed_dps = (uint16_t)value[PRV_AT(KM_REG_MAX_SPEED)];
    out->angle_min = (int16_t)value[PRV_AT(KM_REG_ANGLE_MIN)];
    out->angle_max = (int16_t)value[PRV_AT(KM_REG_ANGLE_MAX)];
    out->travel_min = rf->product->travel_min;
    out->travel_max = rf->product->travel_max;
    out->pos_read_min = rf->product->pos_read_min;
    out->pos_read_max = rf->product->pos_read_max;
    out->prot_enable = (uint8_t)value[PRV_AT(KM_REG_PROT_ENABLE)];
    out->prot_release = (uint8_t)value[PRV_AT(KM_REG_PROT_RELEASE)];
    out->prot_state = (uint8_t)value[PRV_AT(KM_REG_PROT_STATE)];
    out->voltage_high_v = (uint8_t)volt;
    out->voltage_low_v = (uint8_t)(volt >> 8);
    out->temp_trip_c = (uint8_t)temp;
    out->temp_hysteresis_c = (uint8_t)(temp >> 8);
    out->current_trip_ma = (uint16_t)cur;
    out->current_time_100ms = (uint8_t)(cur >> 16);
    out->stall_pwm = (uint16_t)stall;
    out->stall_time_100ms = (uint8_t)(stall >> 16);
    out->control_mode = (uint8_t)value[PRV_AT(KM_REG_CONTROL_MODE)];
    out->torque_limit = (uint16_t)value[PRV_AT(KM_REG_TORQUE_LIMIT)];
    out->current_limit_ma = (uint16_t)value[PRV_AT(KM_REG_CURRENT_LIMIT_NOW)];
    out->speed_limit_dps = (uint16_t)value[PRV_AT(KM_REG_SPEED_LIMIT)];
    out->torque_switch = (uint8_t)value[PRV_AT(KM_REG_TORQUE_SWITCH)];
    out->gains = rf->product->gains ? *rf->product->gains : s_default_gains;
}
