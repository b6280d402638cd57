/* SPDX-License-Identifier: Apache-2.0 */
/* Motor and sensors (km_hal_motor.h, km_hal_sensors.h) for a board without
 * hardware: the motor calls only record the command and the sensors return
 * what a plant adapter last published (km_board.h). Both sides may run in
 * different contexts, so copies happen under the interrupt lock. */
#include "km_board.h"
#include "km_hal_motor.h"
#include "km_hal_sensors.h"
#include "km_hal_system.h"

static km_board_motor_cmd_t s_motor;
static km_sensors_t s_sensors;

void km_hal_motor_init(void)
{
    km_hal_motor_free();
}

void km_hal_motor_drive(int16_t pwm)
{
    if (pwm > KM_MOTOR_PWM_MAX) {
        pwm = KM_MOTOR_PWM_MAX;
    } else if (pwm < -KM_MOTOR_PWM_MAX) {
        pwm = -KM_MOTOR_PWM_MAX;
    }
    uint32_t irq = km_hal_irq_lock();
    s_motor.mode = KM_BOARD_MOTOR_DRIVE;
    s_motor.pwm = pwm;
    km_hal_irq_restore(irq);
}

void km_hal_motor_free(void)
{
    uint32_t irq = km_hal_irq_lock();
    s_motor.mode = KM_BOARD_MOTOR_FREE;
    s_motor.pwm = 0;
    km_hal_irq_restore(irq);
}

void km_hal_motor_brake(void)
{
    uint32_t irq = km_hal_irq_lock();
    s_motor.mode = KM_BOARD_MOTOR_BRAKE;
    s_motor.pwm = 0;
    km_hal_irq_restore(irq);
}

km_board_motor_cmd_t km_board_motor_command(void)
{
    uint32_t irq = km_hal_irq_lock();
    km_board_motor_cmd_t cmd = s_motor;
    km_hal_irq_restore(irq);
    return cmd;
}

/* Zeros until a plant publishes: every reading then says "nothing there"
 * (0 V supply), which the protection logic sees as such, not as motion. */
void km_hal_sensors_init(void)
{
    uint32_t irq = km_hal_irq_lock();
    s_sensors = (km_sensors_t){0};
    km_hal_irq_restore(irq);
}

void km_hal_sensors_read(km_sensors_t *out)
{
    uint32_t irq = km_hal_irq_lock();
    *out = s_sensors;
    km_hal_irq_restore(irq);
}

void km_board_sensors_publish(const km_sensors_t *readings)
{
    uint32_t irq = km_hal_irq_lock();
    s_sensors = *readings;
    km_hal_irq_restore(irq);
}
