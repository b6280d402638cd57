/* The nRF51 (QEMU micro:bit) flash and RAM layout the bootloader and the
 * application share (docs/update.md §1, §6). Plain numbers: boot_startup.c's
 * forwarding stub takes them as assembler literals. */
#ifndef BOOT_LAYOUT_H
#define BOOT_LAYOUT_H

#define BOOT_REGION_BASE 0x00004000       /* application region: 112 KiB */
#define BOOT_REGION_SIZE 0x0001C000
#define BOOT_FACTORY_BASE 0x00020000      /* QEMU factory slot: 112 KiB */
#define BOOT_APP_VECTORS 0x00004100       /* BOOT_REGION_BASE + KM_IMAGE_VECTORS */
#define BOOT_SHARED_ADDR 0x20003FF0       /* km_boot_shared_t: the top 16 bytes of RAM */
#define BOOT_APP_RUNNING_ADDR 0x20003FF4  /* its app_running word */
#define BOOT_APP_MAGIC_WORD 0x41505021    /* KM_BOOT_APP_MAGIC */
#define BOOT_AIRCR 0xE000ED0C
#define BOOT_AIRCR_RESET 0x05FA0004       /* VECTKEY | SYSRESETREQ */
#define BOOT_PAGE 1024

#endif
