/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: the bus UART (docs/architecture.md "HAL contracts"). */
#ifndef KM_HAL_UART_H
#define KM_HAL_UART_H

#include <stdbool.h>
#include <stdint.h>

/* Interrupt context, per byte; lost: an overrun or framing error before it. */
typedef void (*km_uart_rx_handler_t)(void *ctx, uint8_t byte, uint32_t tick, bool lost);

/* 8N1, starts receiving; false: `baud` not within 2 %. */
bool km_hal_uart_init(uint32_t baud, km_uart_rx_handler_t handler, void *ctx);

/* Starts a send; the caller keeps `data` until not busy. False: one is under way. */
bool km_hal_uart_send(const uint8_t *data, uint16_t len);

/* True until the last stop bit went and the bus is back to RX. */
bool km_hal_uart_tx_busy(void);

#endif
