/* SPDX-License-Identifier: Apache-2.0 */
/* Links the template board against a call to every hal function, so a
 * contract function the template forgets is a build error, not a surprise
 * for the next porter. Built only; running it proves nothing. */
#include <stddef.h>

#include "km_board.h"
#include "km_hal_motor.h"
#include "km_hal_sensors.h"
#include "km_hal_system.h"
#include "km_hal_time.h"
#include "km_hal_uart.h"

int main(int argc, char **argv)
{
    (void)argv;
    km_sensors_t s;
    km_hal_system_init();
    km_hal_time_init();
    (void)km_hal_time_tick_hz();
    (void)km_hal_time_now();
    km_hal_timer_at(0u, NULL, NULL);
    km_hal_timer_cancel();
    (void)km_hal_uart_init(115200u, NULL, NULL);
    (void)km_hal_uart_send(NULL, 0u);
    (void)km_hal_uart_tx_busy();
    (void)km_board_flash();
    km_hal_motor_init();
    km_hal_motor_drive(0);
    km_hal_motor_free();
    km_hal_motor_brake();
    km_hal_sensors_init();
    km_hal_sensors_read(&s);
    km_hal_watchdog_start(100u);
    km_hal_watchdog_kick();
    km_hal_irq_restore(km_hal_irq_lock());
    (void)km_hal_entropy();
    km_hal_idle();
    if (argc > 99) {
        km_hal_system_reset();
    }
    return 0;
}
