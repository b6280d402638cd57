/* SPDX-License-Identifier: Apache-2.0 */
/* Template: the half-duplex bus UART (km_hal_uart.h). */
#include "km_hal_uart.h"

/* 8N1 at `baud` (false: not within 2 %); the RX ISR calls handler(ctx, byte, tick, lost). */
bool km_hal_uart_init(uint32_t baud, km_uart_rx_handler_t handler, void *ctx)
{
    (void)baud;
    (void)handler;
    (void)ctx;
    return false;
}

/* Starts sending `len` bytes (interrupt or DMA) with the bus turned to TX; false while busy. */
bool km_hal_uart_send(const uint8_t *data, uint16_t len)
{
    (void)data;
    (void)len;
    return false;
}

/* True until the last stop bit has left the wire (TC, not TXE) and the bus is back in RX. */
bool km_hal_uart_tx_busy(void)
{
    return false;
}
