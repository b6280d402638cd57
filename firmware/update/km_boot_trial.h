/* SPDX-License-Identifier: Apache-2.0 */
/* The trial of a new image (docs/update.md §3a): the words the bootloader
 * and the application share at the top of RAM, and the bootloader's
 * decision over them at every reset. An image is started on trial: the
 * bootloader counts the start before the jump (in RAM a reset keeps), and
 * the application writes "confirmed" once it has served the bus for a
 * while; after KM_BOOT_TRIAL_MAX starts in a row that never confirmed, the
 * bootloader stays in update mode. Pure: the words are passed in (the
 * boards hand over their RAM, the host tests a struct). */
#ifndef KM_BOOT_TRIAL_H
#define KM_BOOT_TRIAL_H

#include <stdbool.h>
#include <stdint.h>

#define KM_BOOT_REQUEST_MAGIC 0x55504454u   /* "stay in update mode" (0x78 ENTER) */
#define KM_BOOT_APP_MAGIC 0x41505021u       /* the application is running (nRF51 forwarding) */
#define KM_BOOT_CONFIRMED_MAGIC 0x4F4B4159u /* the application served the bus: a good boot */
#define KM_BOOT_TRIAL_KEY 0x7A1AC0DEu       /* attempts_check = attempts ^ this */
#define KM_BOOT_TRIAL_MAX 3u                /* unconfirmed starts before update mode */

/* The top 32 bytes of RAM, shared by bootloader and application; neither
 * loaded nor zeroed by either. A power cut leaves garbage: every word is
 * checked before it is believed. Offsets are fixed (boot_layout.h names
 * app_running and confirmed for the nRF51's assembler stubs). */
typedef struct {
    uint32_t request;        /* KM_BOOT_REQUEST_MAGIC: the app asked for update mode */
    uint32_t app_running;    /* KM_BOOT_APP_MAGIC while the app runs */
    uint32_t boot_version;   /* the bootloader's version, for the app's 0x0C */
    uint32_t check;          /* ~boot_version */
    uint32_t attempts;       /* starts of the image since it last confirmed */
    uint32_t attempts_check; /* attempts ^ KM_BOOT_TRIAL_KEY, else attempts read 0 */
    uint32_t confirmed;      /* KM_BOOT_CONFIRMED_MAGIC: this start served the bus */
    uint32_t address;        /* ENTER's ID and baud (km_boot_handoff_set), read only when asked */
} km_boot_shared_t;

typedef enum {
    KM_BOOT_RUN = 0,       /* start the image (the start is counted) */
    KM_BOOT_STAY_NO_IMAGE, /* update mode: no image passes the boot check */
    KM_BOOT_STAY_ASKED,    /* update mode: the application asked (0x78 ENTER) */
    KM_BOOT_STAY_GAVE_UP,  /* update mode: KM_BOOT_TRIAL_MAX starts never confirmed */
} km_boot_decision_t;

/* At every reset, before anything else reads the words: what to do, given
 * whether the region holds an image that may be started (boot check and
 * entry check passed). Consumes the request and the confirmation, clears
 * app_running, counts the start when it says RUN. */
km_boot_decision_t km_boot_decide(volatile km_boot_shared_t *sh, bool image_ok);

/* Unconfirmed starts so far (0 if the words do not hold a count). */
uint32_t km_boot_attempts(const volatile km_boot_shared_t *sh);

/* The image gets KM_BOOT_TRIAL_MAX new tries: after COMMIT (a new image)
 * and at START (the master asks for the image again). */
void km_boot_trial_fresh(volatile km_boot_shared_t *sh);

/* The application: true if a bootloader started it (its version words). */
bool km_boot_started_by_loader(const volatile km_boot_shared_t *sh);

/* The application, once it serves the bus: this start was good. */
void km_boot_confirm(volatile km_boot_shared_t *sh);

/* The application at 0x78 ENTER (docs/update.md §3): the ID and baud it
 * answers on, for the bootloader's update mode. Packed in one word with a
 * check byte: baud / 100 in bits 16-31, ~id in bits 8-15, id in bits 0-7. */
void km_boot_handoff_set(volatile km_boot_shared_t *sh, uint8_t id, uint32_t baud);

/* The bootloader, after a KM_BOOT_STAY_ASKED decision: the ID and baud the
 * application left, if the word holds a sound pair (the check byte
 * matches, the ID 0..250, the baud 9600..1000000); false otherwise (a
 * power cut's garbage, an application that left none). */
bool km_boot_handoff_get(const volatile km_boot_shared_t *sh, uint8_t *id, uint32_t *baud);

#endif
