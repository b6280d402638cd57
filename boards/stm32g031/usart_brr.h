/* SPDX-License-Identifier: Apache-2.0 */
/* USART baud-rate divider for 16x oversampling, pure so the host tests can
 * check every supported rate against the 2 % budget. */
#ifndef USART_BRR_H
#define USART_BRR_H

#include <stdint.h>

/* BRR = round(fck / baud) (RM0444 §33.5.7), at least 16. Returns 0 when the
 * rate cannot be produced or the result is off by more than 2 %. */
uint32_t km_usart_brr(uint32_t fck_hz, uint32_t baud);

#endif
