/* SPDX-License-Identifier: Apache-2.0 */
/* USART divider computation. */
#include "usart_brr.h"

/* BRR for a baud rate, 0 if out of budget. */
uint32_t km_usart_brr(uint32_t fck_hz, uint32_t baud)
{
    if (baud == 0u) {
        return 0u;
    }
    uint32_t brr = (fck_hz + baud / 2u) / baud;
    if (brr < 16u || brr > 0xFFFFu) {
        return 0u;
    }
    uint32_t actual = fck_hz / brr;
    uint32_t diff = actual > baud ? actual - baud : baud - actual;
    if (diff * 50u > baud) { /* > 2 % */
        return 0u;
    }
    return brr;
}
