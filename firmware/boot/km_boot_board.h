/* SPDX-License-Identifier: Apache-2.0 */
/* What a board gives its bootloader (docs/update.md §3, §5): polled UART,
 * a microsecond clock, the application region and the user-data store as
 * km_flash_t, the shared RAM words (km_boot_trial.h), the watchdog, and
 * the jump that starts an image on trial. The bootloader takes no
 * interrupt and polls (a board may sleep between bytes: km_bootb_wait),
 * so it needs no handler of its own. A board's
 * boot_layout.h also names BOOT_RAM_BASE and BOOT_SHARED_ADDR: the range
 * an image's initial stack pointer must lie in. */
#ifndef KM_BOOT_BOARD_H
#define KM_BOOT_BOARD_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"
#include "km_boot_trial.h"
#include "km_image.h"

#define KM_BOOT_VERSION 0x10u /* 0x0C bootloader byte: v1.0 */

volatile km_boot_shared_t *km_bootb_shared(void);

void km_bootb_init(void);                /* clocks and the microsecond clock */
const km_flash_t *km_bootb_region(void); /* the application region */
const km_flash_t *km_bootb_store(void);  /* the user-data store */
const km_image_target_t *km_bootb_target(void);
uint32_t km_bootb_hw_version(void); /* 0x0C hardware byte, e.g. 0x10 */
/* Before the boot check: a board with a factory slot installs it (QEMU). */
void km_bootb_factory(void);

bool km_bootb_uart_init(uint32_t baud);              /* false: the board cannot make it */
bool km_bootb_uart_rx(uint8_t *byte);                /* a received byte, if any */
void km_bootb_uart_tx(const uint8_t *p, uint32_t n); /* returns after the last stop bit */
uint32_t km_bootb_now_us(void);
/* A board whose boot_layout.h defines BOOT_HAS_WAIT: sleeps until a byte
 * is received or at most ~10 ms passed (the watchdog's reloads and the
 * parser's gap go on), without taking an interrupt. */
void km_bootb_wait(void);

/* Reloads the watchdog if a reset left it running (nRF51: a soft reset
 * may); harmless when it is not. */
void km_bootb_watchdog_kick(void);

_Noreturn void km_bootb_reset(void);
/* Starts the image whose vector table is at `vectors` (initial SP `sp`,
 * reset vector `pc`, both checked by km_boot_entry) on trial: arms the
 * watchdog, on the nRF51 also the trial timer (docs/update.md §3a), then
 * jumps. */
_Noreturn void km_bootb_start(uint32_t vectors, uint32_t sp, uint32_t pc);

#endif
