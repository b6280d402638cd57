/* SPDX-License-Identifier: Apache-2.0 */
/* Template: the H-bridge (km_hal_motor.h). */
#include "km_hal_motor.h"

/* Timer PWM at the board's frequency, dead time, bridge off (coast). */
void km_hal_motor_init(void)
{
}

/* Clamp to +-KM_MOTOR_PWM_MAX; the sign picks the bridge diagonal, the
 * magnitude the duty in thousandths. */
void km_hal_motor_drive(int16_t pwm)
{
    (void)pwm;
}

/* All four switches off. */
void km_hal_motor_free(void)
{
}

/* Both low sides on. */
void km_hal_motor_brake(void)
{
}
