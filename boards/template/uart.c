/* SPDX-License-Identifier: Apache-2.0 */
/* Template: the half-duplex bus UART (km_hal_uart.h). */
#include "km_hal_uart.h"

/* Set 8N1 at `baud`; return false if the clock cannot make it within 2 %.
 * Remember the handler; enable the RX interrupt, whose ISR reads each byte,
 * takes km_hal_time_now() and calls handler(ctx, byte, tick, lost), with
 * lost = an overrun/framing error was flagged before this byte. */
bool km_hal_uart_init(uint32_t baud, km_uart_rx_handler_t handler, void *ctx)
{
    (void)baud;
    (void)handler;
    (void)ctx;
    return false;
}

/* Refuse (false) while a send is under way. Else turn the bus to TX (drive
 * enable / single-wire direction), start an interrupt or DMA transfer of
 * `len` bytes from `data` (valid until tx_busy() is false) and return true.
 * Callable from the main loop and from the response-delay timer ISR. */
bool km_hal_uart_send(const uint8_t *data, uint16_t len)
{
    (void)data;
    (void)len;
    return false;
}

/* True until the last stop bit has left the wire (TC, not TXE) and the bus
 * is back in RX; the servo must not hear its own answer. */
bool km_hal_uart_tx_busy(void)
{
    return false;
}
