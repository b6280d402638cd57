/* SPDX-License-Identifier: Apache-2.0 */
/* The STM32G031 flash and RAM layout the bootloader and the application
 * share (docs/update.md §1). */
#ifndef BOOT_LAYOUT_H
#define BOOT_LAYOUT_H

#define BOOT_REGION_BASE 0x08002000u /* application region: 25 pages, 50 KiB */
#define BOOT_REGION_SIZE (25u * 2048u)
#define BOOT_STORE_BASE 0x0800E800u /* user-data store: 3 pages */
#define BOOT_STORE_SIZE (3u * 2048u)
#define BOOT_RAM_BASE 0x20000000u
#define BOOT_SHARED_ADDR 0x20001FE0u /* km_boot_shared_t: the top 32 bytes of RAM */

#endif
