/* The boot decision (docs/update.md §3), shared by the bootloaders and the
 * host tests: start the application only if its header is sound for this
 * board and the CRC-32 of its body, read back through the flash interface,
 * matches. Any read error (an ECC error on a torn cell) means "do not
 * start". Pure: it only reads through the km_flash_t it is given. */
#ifndef KM_BOOT_CHECK_H
#define KM_BOOT_CHECK_H

#include <stdbool.h>

#include "km_hal_flash.h"
#include "km_image.h"

/* True if the application region holds an image to start; fills *h (may
 * be NULL) with its header whatever the verdict. */
bool km_boot_check(const km_flash_t *region, const km_image_target_t *t, km_image_header_t *h);

/* CRC-32 of region bytes [from, to), continuing crc; false on a read error. */
bool km_boot_crc(const km_flash_t *region, uint32_t from, uint32_t to, uint32_t *crc);

#endif
