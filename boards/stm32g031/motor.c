/* SPDX-License-Identifier: Apache-2.0 */
/* km_hal_motor on TIM3 CH1/CH2, 20 kHz PWM into an IN1/IN2 bridge; drive,
 * brake and coast: README.md "H-bridge". */
#include "km_hal_motor.h"

#include "board_pins.h"
#include "km_board.h"
#include "g0_gpio.h"
#include "motor_duty.h"

#define PWM_PERIOD KM_MOTOR_PWM_PERIOD

static volatile int8_t s_direction;

/* Both compare values, preloaded: they change in the same period (> ARR: high). */
static void prv_set(uint32_t in1, uint32_t in2)
{
    TIM_CCR1(TIM3_BASE_R) = in1;
    TIM_CCR2(TIM3_BASE_R) = in2;
}

/* TIM3 PWM, outputs low, then the pins to the timer. */
void km_hal_motor_init(void)
{
    RCC_APBENR1 |= RCC_APBENR1_TIM3;
    TIM_CR1(TIM3_BASE_R) = 0u;
    TIM_PSC(TIM3_BASE_R) = 0u;
    TIM_ARR(TIM3_BASE_R) = PWM_PERIOD - 1u;
    TIM_CCMR1(TIM3_BASE_R) = TIM_CCMR1_OC1M_PWM1 | TIM_CCMR1_OC1PE | TIM_CCMR1_OC2M_PWM1 | TIM_CCMR1_OC2PE;
    prv_set(0u, 0u);
    TIM_CCER(TIM3_BASE_R) = TIM_CCER_CC1E | TIM_CCER_CC2E;
    TIM_EGR(TIM3_BASE_R) = TIM_EGR_UG; /* load preloads */
    TIM_CR1(TIM3_BASE_R) = TIM_CR1_ARPE | TIM_CR1_CEN;
    g0_gpio_af(PIN_IN1_PORT, PIN_IN1_PIN, PIN_PWM_AF);
    g0_gpio_af(PIN_IN2_PORT, PIN_IN2_PIN, PIN_PWM_AF);
}

/* PWM on one input, the other low. */
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

/* Both low: coast. */
void km_hal_motor_free(void)
{
    s_direction = 0;
    prv_set(0u, 0u);
}

/* Both high: brake. */
void km_hal_motor_brake(void)
{
    s_direction = 0;
    prv_set(PWM_PERIOD, PWM_PERIOD);
}

/* The drive's sign. */
int8_t km_board_motor_direction(void)
{
    return s_direction;
}
