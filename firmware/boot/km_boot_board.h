/* SPDX-License-Identifier: Apache-2.0 */
/* What a board gives its bootloader (docs/update.md §3, §5, §12); its
 * boot_layout.h names BOOT_RAM_BASE..BOOT_SHARED_ADDR, an image's SP range. */
#ifndef KM_BOOT_BOARD_H
#define KM_BOOT_BOARD_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"
#include "km_boot_trial.h"
#include "km_image.h"

#define KM_BOOT_VERSION 0x10u /* 0x0C bootloader byte: v1.0 */

volatile km_boot_shared_t *km_bootb_shared(void); /* km_boot_trial.h */

void km_bootb_init(void);                       /* clocks and the microsecond clock */
const km_flash_t *km_bootb_region(void);        /* the application region */
const km_flash_t *km_bootb_store(void);         /* the user-data store */
const km_image_target_t *km_bootb_target(void); /* the images it accepts */
uint32_t km_bootb_hw_version(void);             /* 0x0C hardware byte */
void km_bootb_factory(void);                    /* before the boot check: QEMU's factory image */

bool km_bootb_uart_init(uint32_t baud);              /* false: no such baud */
bool km_bootb_uart_rx(uint8_t *byte);                /* a received byte, if any */
void km_bootb_uart_tx(const uint8_t *p, uint32_t n); /* returns after the last stop bit */
uint32_t km_bootb_now_us(void);                      /* microseconds, wrapping */
/* BOOT_HAS_WAIT: sleeps until a byte or ~10 ms, taking no interrupt. */
void km_bootb_wait(void);
/* Reloads the watchdog if a reset left it running. */
void km_bootb_watchdog_kick(void);
/* Resets the MCU. */
_Noreturn void km_bootb_reset(void);
/* Arms the trial (§3a) and jumps to the image whose vectors are at `vectors`. */
_Noreturn void km_bootb_start(uint32_t vectors, uint32_t sp, uint32_t pc);

#endif
