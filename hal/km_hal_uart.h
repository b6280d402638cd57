/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: the half-duplex servo bus UART; RX bytes stamped in interrupt context (docs/architecture.md
 * "HAL contracts"). */
#ifndef KM_HAL_UART_H
#define KM_HAL_UART_H

#include <stdbool.h>
#include <stdint.h>

/* Called in interrupt context for every received byte. `lost` is true when the
 * hardware reported an overrun or framing error before this byte. */
typedef void (*km_uart_rx_handler_t)(void *ctx, uint8_t byte, uint32_t tick, bool lost);

/* Configure 8N1 at `baud` and start receiving. Returns false if the baud
 * rate cannot be produced within 2 % by this board's clock. */
bool km_hal_uart_init(uint32_t baud, km_uart_rx_handler_t handler, void *ctx);

/* Start sending `len` bytes; the buffer must stay valid until
 * km_hal_uart_tx_busy() returns false. Returns false if a send is under way. */
bool km_hal_uart_send(const uint8_t *data, uint16_t len);

/* True until the last byte has left the wire and the bus is back to RX. */
bool km_hal_uart_tx_busy(void);

#endif
