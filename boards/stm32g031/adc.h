/* SPDX-License-Identifier: Apache-2.0 */
/* ADC sampler: four inputs, continuous scan by DMA. */
#ifndef ADC_H
#define ADC_H

#include <stdint.h>

#include "board_pins.h"

/* Starts the scan. */
void km_adc_start(void);

/* Latest 12-bit reading of each channel, indexed by ADC_CH_*. */
void km_adc_latest(uint16_t out[ADC_CHANNELS]);

#endif
