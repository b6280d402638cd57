/* SPDX-License-Identifier: Apache-2.0 */
/* ADC sampler: the four analog inputs converted continuously into a RAM
 * array by DMA. */
#ifndef ADC_H
#define ADC_H

#include <stdint.h>

#include "board_pins.h"

void km_adc_start(void);

/* Latest 12-bit (16x oversampled) reading of each channel, indexed by
 * ADC_CH_*. */
void km_adc_latest(uint16_t out[ADC_CHANNELS]);

#endif
