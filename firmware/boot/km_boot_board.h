/* What a board gives its bootloader (docs/update.md §3, §5): polled UART,
 * a microsecond clock, the application region and the user-data store as
 * km_flash_t, and the jump. The bootloader runs with interrupts masked and
 * polls, so it needs no handler of its own. */
#ifndef KM_BOOT_BOARD_H
#define KM_BOOT_BOARD_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_flash.h"
#include "km_image.h"

#define KM_BOOT_VERSION 0x10u             /* 0x0C bootloader byte: v1.0 */
#define KM_BOOT_REQUEST_MAGIC 0x55504454u /* "stay in update mode" (0x78 ENTER) */
#define KM_BOOT_APP_MAGIC 0x41505021u     /* the application is running (nRF51 forwarding) */

/* The top 16 bytes of RAM, shared by bootloader and application; neither
 * loaded nor zeroed by either. */
typedef struct {
    uint32_t request;       /* KM_BOOT_REQUEST_MAGIC: the app asked for update mode */
    uint32_t app_running;   /* KM_BOOT_APP_MAGIC while the app runs */
    uint32_t boot_version;  /* KM_BOOT_VERSION, for the app's 0x0C */
    uint32_t check;         /* ~boot_version */
} km_boot_shared_t;

volatile km_boot_shared_t *km_bootb_shared(void);

void km_bootb_init(void);                       /* clocks and the microsecond clock */
const km_flash_t *km_bootb_region(void);        /* the application region */
const km_flash_t *km_bootb_store(void);         /* the user-data store */
const km_image_target_t *km_bootb_target(void);
uint32_t km_bootb_hw_version(void);             /* 0x0C hardware byte, e.g. 0x10 */
/* Before the boot check: a board with a factory slot installs it (QEMU). */
void km_bootb_factory(void);

bool km_bootb_uart_init(uint32_t baud);         /* false: the board cannot make it */
bool km_bootb_uart_rx(uint8_t *byte);           /* a received byte, if any */
void km_bootb_uart_tx(const uint8_t *p, uint32_t n); /* returns after the last stop bit */
uint32_t km_bootb_now_us(void);

_Noreturn void km_bootb_reset(void);
/* Starts the application whose vector table is at `vectors`. */
_Noreturn void km_bootb_start(uint32_t vectors);

#endif
