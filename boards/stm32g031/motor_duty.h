/* SPDX-License-Identifier: Apache-2.0 */
/* TIM3 compare value of a drive magnitude without a division (pure, host-tested). */
#ifndef MOTOR_DUTY_H
#define MOTOR_DUTY_H

#include <stdint.h>

#include "km_hal_motor.h"

#define KM_MOTOR_PWM_PERIOD 3200u /* 20 kHz at 64 MHz */

/* (x * 13108) >> 16 == x / 5 for x < 16,384 (README.md "Drivers", Motor). */
_Static_assert(KM_MOTOR_PWM_PERIOD * 5u == (uint32_t)KM_MOTOR_PWM_MAX * 16u, "the duty's ratio is 16/5");

/* floor(mag x KM_MOTOR_PWM_PERIOD / KM_MOTOR_PWM_MAX) for mag <= KM_MOTOR_PWM_MAX. */
static inline uint32_t km_motor_duty(uint32_t mag)
{
    return (mag * 16u * 13108u) >> 16;
}

#endif
