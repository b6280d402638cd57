/* SPDX-License-Identifier: Apache-2.0 */
/* The boot and entry checks (docs/update.md §3), shared by the bootloaders
 * and the host tests; a read error means "do not start". Pure. */
#ifndef KM_BOOT_CHECK_H
#define KM_BOOT_CHECK_H

#include <stdbool.h>

#include "km_hal_flash.h"
#include "km_image.h"

/* True if the region holds an image sound for this board whose body CRC-32
 * matches; fills *h (may be NULL) whatever the verdict. */
bool km_boot_check(const km_flash_t *region, const km_image_target_t *t, km_image_header_t *h);

/* Where a checked image starts: its vector table's first two words. */
typedef struct {
    uint32_t sp; /* initial stack pointer */
    uint32_t pc; /* reset vector (Thumb: bit 0 set) */
} km_boot_entry_t;

/* The entry check of a checked image: SP in [sp_lo, sp_hi], the reset
 * vector a Thumb address inside the image (vector table to length). False
 * on a read error; fills *e whatever the verdict. */
bool km_boot_entry(const km_flash_t *region, const km_image_header_t *h, uint32_t sp_lo, uint32_t sp_hi,
                   km_boot_entry_t *e);

/* CRC-32 of region bytes [from, to), continuing crc; false on a read error. */
bool km_boot_crc(const km_flash_t *region, uint32_t from, uint32_t to, uint32_t *crc);

#endif
