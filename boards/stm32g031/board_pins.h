/* SPDX-License-Identifier: Apache-2.0 */
/* Pins of the STM32G031 servo board (F8 TSSOP20 or K8 LQFP32); README.md "Pinout". */
#ifndef BOARD_PINS_H
#define BOARD_PINS_H

#include "g0_regs.h"

/* Servo bus: USART1_TX on PB6 (AF0), half-duplex, open drain. */
#define PIN_BUS_PORT GPIOB_BASE_R
#define PIN_BUS_PIN 6u
#define PIN_BUS_AF 0u

/* Optional RS-485 DE on PA4 (KM_BOARD_RS485_DE). */
#define PIN_DE_PORT GPIOA_BASE_R
#define PIN_DE_PIN 4u

/* H-bridge inputs: TIM3_CH1 on PA6 -> IN1, TIM3_CH2 on PA7 -> IN2 (AF1). */
#define PIN_IN1_PORT GPIOA_BASE_R
#define PIN_IN1_PIN 6u
#define PIN_IN2_PORT GPIOA_BASE_R
#define PIN_IN2_PIN 7u
#define PIN_PWM_AF 1u

/* ADC_IN0..3 on PA0..PA3, converted in this order. */
#define ADC_CH_POT 0u     /* PA0: potentiometer wiper */
#define ADC_CH_SHUNT 1u   /* PA1: shunt amplifier */
#define ADC_CH_VSUPPLY 2u /* PA2: supply divider */
#define ADC_CH_NTC 3u     /* PA3: NTC divider */
#define ADC_CHANNELS 4u

#endif
