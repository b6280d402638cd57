/* SPDX-License-Identifier: Apache-2.0 */
/* STM32G031 bring-up image: echoes bus bytes after 2 ms of quiet (docs/bringup.md). */
#include <stdbool.h>
#include <stdint.h>

#include "km_board.h"
#include "km_hal_motor.h"
#include "km_hal_sensors.h"
#include "km_hal_system.h"
#include "km_hal_time.h"
#include "km_hal_uart.h"

#define BRINGUP_BAUD 115200u
#define ECHO_GAP_US 2000u

static uint8_t s_rx[64];
static volatile uint8_t s_rx_len;
static volatile bool s_echo_due;
static uint8_t s_tx[64];

static void prv_echo_due(void *ctx)
{
    (void)ctx;
    s_echo_due = true;
}

static void prv_rx(void *ctx, uint8_t byte, uint32_t tick, bool lost)
{
    (void)ctx;
    (void)lost;
    if (s_rx_len < sizeof s_rx) {
        s_rx[s_rx_len] = byte;
        s_rx_len = (uint8_t)(s_rx_len + 1u);
    }
    km_hal_timer_at(tick + ECHO_GAP_US, prv_echo_due, 0);
}

int main(void)
{
    km_hal_system_init();
    km_hal_time_init();
    km_hal_motor_init();
    km_hal_motor_free();
    km_hal_sensors_init();
    (void)km_board_flash();
    (void)km_hal_uart_init(BRINGUP_BAUD, prv_rx, 0);
    km_hal_watchdog_start(500u);

    for (;;) {
        km_hal_watchdog_kick();
        if (s_echo_due && !km_hal_uart_tx_busy()) {
            uint32_t key = km_hal_irq_lock();
            uint8_t n = s_rx_len;
            for (uint8_t i = 0u; i < n; i++) {
                s_tx[i] = s_rx[i];
            }
            s_rx_len = 0u;
            s_echo_due = false;
            km_hal_irq_restore(key);
            (void)km_hal_uart_send(s_tx, n);
        }
        km_sensors_t sensors;
        km_hal_sensors_read(&sensors);
        (void)sensors;
        km_hal_idle();
    }
}
