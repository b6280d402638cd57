/* SPDX-License-Identifier: Apache-2.0 */
/* The TIM3 compare value of a drive magnitude, without a division: the
 * control tick drives the bridge every millisecond, and on the M0 a 32-bit
 * divide is a libgcc call (docs/benchmarks.md "Control tick"). Pure, so the
 * host tests check every magnitude against the exact quotient. */
#ifndef MOTOR_DUTY_H
#define MOTOR_DUTY_H

#include <stdint.h>

#include "km_hal_motor.h"

#define KM_MOTOR_PWM_PERIOD 3200u /* timer counts per PWM period at 64 MHz: 20 kHz */

/* mag x 3200 / 1000 = (mag x 16) / 5; for x = mag x 16 <= 16,000,
 * (x x 13108) >> 16 is floor(x / 5): 13108 = ceil(2^16 / 5), whose excess
 * 5 x 13108 - 2^16 = 4 keeps the error x x 4 / 2^16 below 1/5 while
 * x < 16,384. */
_Static_assert(KM_MOTOR_PWM_PERIOD * 5u == (uint32_t)KM_MOTOR_PWM_MAX * 16u, "the duty's ratio is 16/5");

/* floor(mag x KM_MOTOR_PWM_PERIOD / KM_MOTOR_PWM_MAX) for mag <= KM_MOTOR_PWM_MAX. */
static inline uint32_t km_motor_duty(uint32_t mag)
{
    return (mag * 16u * 13108u) >> 16;
}

#endif
