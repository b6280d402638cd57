/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: the H-bridge. */
#ifndef KM_HAL_MOTOR_H
#define KM_HAL_MOTOR_H

#include <stdint.h>

#define KM_MOTOR_PWM_MAX 1000

void km_hal_motor_init(void);

/* Drives at -1000..1000 thousandths of full duty (sign: direction; clamped). */
void km_hal_motor_drive(int16_t pwm);

/* Coast: all switches off. */
void km_hal_motor_free(void);

/* Brake: both low sides on. */
void km_hal_motor_brake(void);

#endif
