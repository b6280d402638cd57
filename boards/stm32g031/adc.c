/* SPDX-License-Identifier: Apache-2.0 */
/* Continuous scan of ADC_IN0..3, 16x oversampled, by circular DMA1 channel 1
 * into s_samples (RM0444 §15.5, §15.9); why and timing: README.md "Drivers". */
#include "adc.h"

#include "g0_gpio.h"

static volatile uint16_t s_samples[ADC_CHANNELS];

/* Busy wait, about 4 cycles per iteration at 64 MHz (before the timer runs). */
static void prv_delay_us(uint32_t us)
{
    for (volatile uint32_t i = 0u; i < us * 16u; i++) {
    }
}

/* Calibrates the ADC and starts the scan. */
void km_adc_start(void)
{
    for (uint32_t pin = 0u; pin < ADC_CHANNELS; pin++) {
        g0_gpio_mode(GPIOA_BASE_R, pin, G0_GPIO_MODE_ANALOG); /* PA0..PA3 */
    }
    RCC_APBENR2 |= RCC_APBENR2_ADC;
    RCC_AHBENR |= RCC_AHBENR_DMA1;

    /* CKMODE only while ADEN = 0; regulator 20 µs, calibration (§15.3.2, §15.3.3). */
    ADC_CFGR2 = ADC_CFGR2_CKMODE_PCLK2;
    ADC_CR = ADC_CR_ADVREGEN;
    prv_delay_us(20u);
    ADC_CR |= ADC_CR_ADCAL;
    while ((ADC_CR & ADC_CR_ADCAL) != 0u) {
    }
    ADC_ISR = ADC_ISR_EOCAL;

    ADC_CFGR1 = ADC_CFGR1_DMAEN | ADC_CFGR1_DMACFG | ADC_CFGR1_CONT | ADC_CFGR1_OVRMOD;
    ADC_CFGR2 = ADC_CFGR2_CKMODE_PCLK2 | ADC_CFGR2_OVSE | (3u << ADC_CFGR2_OVSR_SHIFT) | /* 16 samples */
                (4u << ADC_CFGR2_OVSS_SHIFT); /* >> 4: back to 12 bits */
    ADC_SMPR = ADC_SMPR_SMP1_160_5;           /* high-impedance dividers */
    DMAMUX_C0CR = DMAMUX_REQ_ADC;
    DMA1_CCR1 = 0u;
    DMA1_CPAR1 = (uint32_t)(uintptr_t)&ADC_DR;
    DMA1_CMAR1 = (uint32_t)(uintptr_t)s_samples;
    DMA1_CNDTR1 = ADC_CHANNELS;
    DMA1_CCR1 = DMA_CCR_CIRC | DMA_CCR_MINC | DMA_CCR_PSIZE_16 | DMA_CCR_MSIZE_16 | DMA_CCR_EN;

    ADC_ISR = ADC_ISR_ADRDY;
    ADC_CR |= ADC_CR_ADEN;
    while ((ADC_ISR & ADC_ISR_ADRDY) == 0u) {
    }
    /* CCRDY before the first start (§15.3.7); upward scan: index = channel. */
    ADC_CHSELR = (1u << ADC_CH_POT) | (1u << ADC_CH_SHUNT) | (1u << ADC_CH_VSUPPLY) | (1u << ADC_CH_NTC);
    while ((ADC_ISR & ADC_ISR_CCRDY) == 0u) {
    }
    ADC_ISR = ADC_ISR_CCRDY;
    ADC_CR |= ADC_CR_ADSTART;
}

/* Copies the latest set (may mix two scans 0.35 ms apart). */
void km_adc_latest(uint16_t out[ADC_CHANNELS])
{
    for (uint32_t i = 0u; i < ADC_CHANNELS; i++) {
        out[i] = s_samples[i];
    }
}
