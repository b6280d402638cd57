/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: the simulated "interrupts". The native program is single-threaded:
 * km_hal_idle() waits (poll) for bus bytes or the next due event and then
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

/* --baud N: the master's line rate (0: the servo's own, the default);
 * --report-baud: "baud N" on stdout at every UART start (hs_uart.c). */
void hs_uart_set_wire_baud(uint32_t baud);
void hs_uart_set_report_baud(bool on);
/* The simulated plant's physics to the re-executed image (hs_plant_keep.c). */
void hs_plant_prepare_exec(void);
/* --scenario FILE (hs_scenario.c); false, with the reason on stderr, if the
 * file cannot be read or is malformed. */
bool hs_scenario_load(const char *path);

/* File descriptor to poll for bus input (-1 when none, or when the host-side
 * receive buffer is full: the socket then keeps the rest, TCP flow control
 * holds the sender, and nothing is dropped). */
int hs_uart_poll_fd(void);
/* Called when the poll said the fd is readable: accepts a client, or reads
 * bytes into the host-side buffer, each given the time it reaches the end
 * of the wire at the servo's baud. Delivers nothing itself. */
void hs_uart_on_readable(void);

/* RX "interrupts", from km_hal_idle(): idle_begin first (the app's queue
 * budget, TX done), then deliver_one hands the oldest buffered byte to the
 * RX handler if its wire time has come (false if none). HS_RX_BATCH: most
 * bytes per idle, the shortest frame (a ping or a status answer), so one
 * batch never holds two frame ends. */
#define HS_RX_BATCH 6u
void hs_uart_rx_idle_begin(void);
bool hs_uart_rx_deliver_one(void);
/* The wire time of the oldest byte the RX handler can take now (UINT64_MAX
 * when none): the emulated clock does not run past it. */
uint64_t hs_uart_hold_ns(void);
/* Microseconds from `real_ns` until the UART's next event (-1 when none). */
int64_t hs_uart_due_in_us(uint64_t real_ns);

/* The host's CLOCK_MONOTONIC in ns, and the emulated clock (see hs_time.c);
 * km_hal_time_now() is the emulated one / 1000, wrapped. */
uint64_t hs_time_real_ns(void);
uint64_t hs_time_now_ns(void);

/* Microseconds until the next simulated interrupt is due: the one-shot
 * timer, the next received byte, or TX done (-1 when none). km_hal_idle()
 * sleeps no longer than this. */
int64_t hs_timer_due_in_us(void);
/* All simulated interrupts that are due (from km_hal_idle()), in time
 * order: the timer, and up to HS_RX_BATCH received bytes. */
void hs_timer_service(void);
/* The timer "interrupt" alone, by the host's clock: for an app that spins
 * on km_hal_uart_tx_busy(), where a real MCU keeps taking it. */
void hs_timer_fire_due_now(void);
/* Inside the timer's handler: the time it was due (however late the host
 * ran it); 0 elsewhere. */
uint64_t hs_timer_firing_due_ns(void);

#endif
