/* SPDX-License-Identifier: Apache-2.0 */
/* The STM32G031 flash and RAM layout the bootloader and the application
 * share (docs/update.md §1). */
#ifndef BOOT_LAYOUT_H
#define BOOT_LAYOUT_H

/* The part's flash and the bootloader's region in KiB, as the build sets
 * them (boards/stm32g031/board.cmake KM_G031_FLASH_KB): 64 and 8 on the
 * G031x8, 32 and 4 on the G031x6 (docs/footprint.md "STM32G031F6"). */
#ifndef KM_G031_FLASH_KB
#define KM_G031_FLASH_KB 64u
#endif
#ifndef KM_G031_BOOT_KB
#define KM_G031_BOOT_KB 8u
#endif

#define BOOT_FLASH_BASE 0x08000000u
#define BOOT_STORE_SIZE (3u * 2048u) /* user-data store: the last 3 pages */
#define BOOT_STORE_BASE (BOOT_FLASH_BASE + KM_G031_FLASH_KB * 1024u - BOOT_STORE_SIZE)
/* Application region: after the bootloader, up to the store (64 KiB part:
 * 0x08002000, 25 pages, 50 KiB; 32 KiB part: 0x08001000, 11 pages). */
#define BOOT_REGION_BASE (BOOT_FLASH_BASE + KM_G031_BOOT_KB * 1024u)
#define BOOT_REGION_SIZE (BOOT_STORE_BASE - BOOT_REGION_BASE)
#define BOOT_RAM_BASE 0x20000000u
#define BOOT_SHARED_ADDR 0x20001FE0u /* km_boot_shared_t: the top 32 bytes of RAM */
/* Update mode sleeps between bytes (km_bootb_wait) where the bootloader's
 * region has room: the 8 KiB one; the 32 KiB part's 4 KiB bootloader polls
 * (docs/footprint.md). */
#if KM_G031_BOOT_KB >= 8u
#define BOOT_HAS_WAIT 1
#endif

#endif
