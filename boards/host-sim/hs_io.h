/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: the simulated "interrupts", run from km_hal_idle() (docs/architecture.md
 * "host-sim's clock"). */
#ifndef HS_IO_H
#define HS_IO_H

#include <stdbool.h>
#include <stdint.h>

/* Bus endpoint: a TCP listener ("HOST:PORT") or a pseudo-terminal. */
bool hs_uart_open_tcp(const char *host_port);
bool hs_uart_open_pty(void);

/* Restart: hand the bus descriptors to the re-executed image; take them over (false: first start). */
void hs_uart_prepare_exec(void);
bool hs_uart_adopt(void);

/* --baud N (0: the servo's own) and --report-baud (hs_uart.c). */
void hs_uart_set_wire_baud(uint32_t baud);
void hs_uart_set_report_baud(bool on);
/* The simulated plant's physics to the re-executed image (hs_plant_keep.c). */
void hs_plant_prepare_exec(void);
/* --scenario FILE (hs_scenario.c); false, with the reason on stderr, on a bad file. */
bool hs_scenario_load(const char *path);
/* One event "KEY VALUE" to apply now (hs_inject.c): false with *why for a
 * malformed line, an unknown key or a value out of its key's range. */
bool hs_scenario_parse_now(const char *text, uint32_t *key, int32_t *value, const char **why);
/* --inject PATH (hs_inject.c): a Unix datagram socket at PATH taking one
 * "KEY VALUE" scenario event per datagram, applied to the plant at once
 * and answered "ok KEY VALUE" or "error: reason" to a bound sender; the
 * datagram "id" is answered "ok id N", the ID the servo answers at now. */
bool hs_inject_open(const char *path);
int hs_inject_poll_fd(void);
void hs_inject_on_readable(void);

/* File descriptor to poll for bus input; -1 when none or the host-side buffer is full. */
int hs_uart_poll_fd(void);
/* The fd is readable: accepts a client or buffers bytes with their wire times. */
void hs_uart_on_readable(void);

/* RX "interrupts" from km_hal_idle(): idle_begin, then deliver_one per due byte
 * (false: none); at most HS_RX_BATCH (the shortest frame) per idle. */
#define HS_RX_BATCH 6u
void hs_uart_rx_idle_begin(void);
bool hs_uart_rx_deliver_one(void);
/* The wire time of the oldest byte the RX handler can take now (UINT64_MAX: none). */
uint64_t hs_uart_hold_ns(void);
/* Microseconds from `real_ns` until the UART's next event (-1 when none). */
int64_t hs_uart_due_in_us(uint64_t real_ns);

/* The host's CLOCK_MONOTONIC and the emulated clock, ns (hs_time.c). */
uint64_t hs_time_real_ns(void);
uint64_t hs_time_now_ns(void);

/* Microseconds until the next simulated interrupt is due (-1: none). */
int64_t hs_timer_due_in_us(void);
/* Runs every due simulated interrupt, in time order. */
void hs_timer_service(void);
/* The timer "interrupt" alone, by the host's clock (for an app spinning on tx_busy). */
void hs_timer_fire_due_now(void);
/* Inside the timer's handler: the time it was due; 0 elsewhere. */
uint64_t hs_timer_firing_due_ns(void);

#endif
