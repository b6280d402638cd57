/* SPDX-License-Identifier: Apache-2.0 */
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

/* Where a checked image starts: its vector table's first two words. */
typedef struct {
    uint32_t sp; /* initial stack pointer */
    uint32_t pc; /* reset vector (Thumb: bit 0 set) */
} km_boot_entry_t;

/* The entry check (docs/update.md §3) of an image km_boot_check passed,
 * read through the region: the initial SP lies in [sp_lo, sp_hi] and the
 * reset vector is a Thumb address whose first halfword lies inside the
 * image, from its vector table to its length (not merely inside the
 * region). False on a read error. Fills *e whatever the verdict. */
bool km_boot_entry(const km_flash_t *region, const km_image_header_t *h, uint32_t sp_lo, uint32_t sp_hi,
                   km_boot_entry_t *e);

/* CRC-32 of region bytes [from, to), continuing crc; false on a read error. */
bool km_boot_crc(const km_flash_t *region, uint32_t from, uint32_t to, uint32_t *crc);

#endif
