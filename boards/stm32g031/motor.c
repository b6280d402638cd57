/* SPDX-License-Identifier: Apache-2.0 */
/* km_hal_motor on TIM3 CH1/CH2 (PA6 -> IN1, PA7 -> IN2) into a two-input
 * H-bridge driver of the DRV8837 kind: 64 MHz / 3200 = 20 kHz edge-aligned
 * PWM, above hearing. Drive = PWM on one input, the other low (the off phase
 * coasts: fast decay). Brake = both inputs high (DRV8837 truth table: both
 * low-side FETs on). Coast = both low (outputs high-Z). The driver's own
 * pull-downs keep it coasting until this runs. */
#include "km_hal_motor.h"

#include "board_pins.h"
#include "km_board.h"
#include "g0_gpio.h"
#include "motor_duty.h"

#define PWM_PERIOD KM_MOTOR_PWM_PERIOD

static volatile int8_t s_direction;

static void prv_set(uint32_t in1, uint32_t in2)
{
    /* CCR values take effect at the next update (preload), so both inputs
     * change in the same PWM period. CCR > ARR holds the output high. */
    TIM_CCR1(TIM3_BASE_R) = in1;
    TIM_CCR2(TIM3_BASE_R) = in2;
}

void km_hal_motor_init(void)
{
    RCC_APBENR1 |= RCC_APBENR1_TIM3;
    TIM_CR1(TIM3_BASE_R) = 0u;
    TIM_PSC(TIM3_BASE_R) = 0u;
    TIM_ARR(TIM3_BASE_R) = PWM_PERIOD - 1u;
    TIM_CCMR1(TIM3_BASE_R) = TIM_CCMR1_OC1M_PWM1 | TIM_CCMR1_OC1PE | TIM_CCMR1_OC2M_PWM1 | TIM_CCMR1_OC2PE;
    prv_set(0u, 0u);
    TIM_CCER(TIM3_BASE_R) = TIM_CCER_CC1E | TIM_CCER_CC2E;
    TIM_EGR(TIM3_BASE_R) = TIM_EGR_UG; /* load ARR/CCR preloads */
    TIM_CR1(TIM3_BASE_R) = TIM_CR1_ARPE | TIM_CR1_CEN;
    /* Hand the pins to the timer only once its outputs are low. */
    g0_gpio_af(PIN_IN1_PORT, PIN_IN1_PIN, PIN_PWM_AF);
    g0_gpio_af(PIN_IN2_PORT, PIN_IN2_PIN, PIN_PWM_AF);
}

void km_hal_motor_drive(int16_t pwm)
{
    int32_t p = pwm;
    if (p > KM_MOTOR_PWM_MAX) {
        p = KM_MOTOR_PWM_MAX;
    } else if (p < -KM_MOTOR_PWM_MAX) {
        p = -KM_MOTOR_PWM_MAX;
    }
    uint32_t mag = (uint32_t)(p < 0 ? -p : p);
    uint32_t duty = km_motor_duty(mag);
    s_direction = (int8_t)(p > 0 ? 1 : (p < 0 ? -1 : 0));
    if (p >= 0) {
        prv_set(duty, 0u);
    } else {
        prv_set(0u, duty);
    }
}

void km_hal_motor_free(void)
{
    s_direction = 0;
    prv_set(0u, 0u);
}

void km_hal_motor_brake(void)
{
    s_direction = 0;
    prv_set(PWM_PERIOD, PWM_PERIOD);
}

int8_t km_board_motor_direction(void)
{
    return s_direction;
}
