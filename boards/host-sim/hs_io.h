/* host-sim: the simulated "interrupts". The native program is single-threaded:
 * km_hal_idle() waits (poll) for bus bytes or the one-shot timer and then
 * calls the registered handlers, just as the RX and timer interrupts would
 * on a microcontroller. */
#ifndef HS_IO_H
#define HS_IO_H

#include <stdbool.h>
#include <stdint.h>

/* Bus endpoint: a TCP listener ("HOST:PORT") or a pseudo-terminal. */
bool hs_uart_open_tcp(const char *host_port);
bool hs_uart_open_pty(void);

/* Restart support: hand the bus descriptors to the re-executed image, and
 * take them over there (returns false on a first start). */
void hs_uart_prepare_exec(void);
bool hs_uart_adopt(void);

/* File descriptor to poll for bus input (-1 when none). */
int hs_uart_poll_fd(void);
/* Called when the poll said the fd is readable: reads and delivers bytes. */
void hs_uart_on_readable(void);

/* Microseconds until the one-shot timer is due (-1 when unarmed). */
int64_t hs_timer_due_in_us(void);
/* Fires the one-shot timer if due. */
void hs_timer_service(void);

#endif
