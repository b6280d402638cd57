/* SPDX-License-Identifier: Apache-2.0 */
/* The nRF51 (QEMU micro:bit) flash and RAM layout the bootloader and the
 * application share (docs/update.md §1, §6). Plain numbers: boot_startup.c's
 * forwarding stub takes them as assembler literals. */
#ifndef BOOT_LAYOUT_H
#define BOOT_LAYOUT_H

#define BOOT_REGION_BASE 0x00004000 /* application region: 112 KiB */
#define BOOT_REGION_SIZE 0x0001C000
#define BOOT_FACTORY_BASE 0x00020000 /* QEMU factory slot: 112 KiB */
#define BOOT_APP_VECTORS 0x00004100  /* BOOT_REGION_BASE + KM_IMAGE_VECTORS */
#define BOOT_RAM_BASE 0x20000000
#define BOOT_SHARED_ADDR 0x20003FE0      /* km_boot_shared_t: the top 32 bytes of RAM */
#define BOOT_APP_RUNNING_ADDR 0x20003FE4 /* its app_running word */
#define BOOT_CONFIRMED_ADDR 0x20003FF8   /* its confirmed word */
#define BOOT_APP_MAGIC_WORD 0x41505021   /* KM_BOOT_APP_MAGIC */
#define BOOT_CONFIRMED_WORD 0x4F4B4159   /* KM_BOOT_CONFIRMED_MAGIC */
/* The trial timer (docs/update.md §3a): TIMER2, which the application
 * does not use, 16 bits (TIMER1 and TIMER2 have no more on silicon) at
 * 16 MHz >> 9 = 31,250 Hz; its COMPARE0 interrupt, while the application
 * has not confirmed, resets into the bootloader. */
#define BOOT_TRIAL_TIMER 0x4000A000
#define BOOT_TRIAL_IRQ 10 /* TIMER2 */
#define BOOT_TRIAL_PRESCALER 9
#define BOOT_TRIAL_TICKS 62500 /* 2.0 s */
#define BOOT_WDT_MS 500        /* = the application's KM_APP_WATCHDOG_MS */
#define BOOT_AIRCR 0xE000ED0C
#define BOOT_AIRCR_RESET 0x05FA0004 /* VECTKEY | SYSRESETREQ */
#define BOOT_PAGE 1024
/* Update mode sleeps between bytes (km_bootb_wait): QEMU then runs the
 * guest only when a byte or the 10 ms wake-up arrives. */
#define BOOT_HAS_WAIT 1

#endif
