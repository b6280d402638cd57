/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: the H-bridge. Signed PWM in thousandths of full duty; the
 * board owns the PWM frequency and dead time. */
#ifndef KM_HAL_MOTOR_H
#define KM_HAL_MOTOR_H

#include <stdint.h>

#define KM_MOTOR_PWM_MAX 1000

void km_hal_motor_init(void);

/* Drive with duty -1000..1000 (sign = direction; values outside are clamped). */
void km_hal_motor_drive(int16_t pwm);

/* Coast: all bridge switches off (no damping). */
void km_hal_motor_free(void);

/* Brake: both low sides on (short-circuit damping). */
void km_hal_motor_brake(void);

#endif
