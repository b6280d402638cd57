/* SPDX-License-Identifier: Apache-2.0 */
/* USART baud-rate divider, 16x oversampling (pure, host-tested). */
#ifndef USART_BRR_H
#define USART_BRR_H

#include <stdint.h>

/* round(fck / baud) (RM0444 §33.5.7); 0 if below 16 or off by more than 2 %. */
uint32_t km_usart_brr(uint32_t fck_hz, uint32_t baud);

#endif
