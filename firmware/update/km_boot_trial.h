/* SPDX-License-Identifier: Apache-2.0 */
/* The trial of a new image (docs/update.md §3a): the words bootloader and
 * application share at the top of RAM, and the decision over them at every
 * reset. Pure: the words are passed in. */
#ifndef KM_BOOT_TRIAL_H
#define KM_BOOT_TRIAL_H

#include <stdbool.h>
#include <stdint.h>

#define KM_BOOT_REQUEST_MAGIC 0x55504454u   /* "stay in update mode" (0x78 ENTER) */
#define KM_BOOT_APP_MAGIC 0x41505021u       /* the application is running (nRF51 forwarding) */
#define KM_BOOT_CONFIRMED_MAGIC 0x4F4B4159u /* the application served the bus: a good boot */
#define KM_BOOT_TRIAL_KEY 0x7A1AC0DEu       /* attempts_check = attempts ^ this */
#define KM_BOOT_TRIAL_MAX 3u                /* unconfirmed starts before update mode */

/* The top 32 bytes of RAM, loaded and zeroed by neither side: every word is
 * checked before it is believed. Offsets fixed (boot_layout.h). */
typedef struct {
    uint32_t request;        /* KM_BOOT_REQUEST_MAGIC: update mode asked for */
    uint32_t app_running;    /* KM_BOOT_APP_MAGIC while the app runs */
    uint32_t boot_version;   /* for the app's 0x0C */
    uint32_t check;          /* ~boot_version */
    uint32_t attempts;       /* starts since the image last confirmed */
    uint32_t attempts_check; /* attempts ^ KM_BOOT_TRIAL_KEY, else attempts read 0 */
    uint32_t confirmed;      /* KM_BOOT_CONFIRMED_MAGIC: this start served the bus */
    uint32_t address;        /* ENTER's ID and baud (km_boot_handoff_set) */
} km_boot_shared_t;

typedef enum {
    KM_BOOT_RUN = 0,       /* start the image (the start is counted) */
    KM_BOOT_STAY_NO_IMAGE, /* update mode: no image passes the checks */
    KM_BOOT_STAY_ASKED,    /* update mode: 0x78 ENTER asked */
    KM_BOOT_STAY_GAVE_UP,  /* update mode: KM_BOOT_TRIAL_MAX unconfirmed starts */
} km_boot_decision_t;

/* At every reset, first: what to do, given whether the image passed the
 * boot and entry checks. Consumes request and confirmation, clears
 * app_running, counts the start on RUN. */
km_boot_decision_t km_boot_decide(volatile km_boot_shared_t *sh, bool image_ok);

/* Unconfirmed starts so far (0 if the words hold no count). */
uint32_t km_boot_attempts(const volatile km_boot_shared_t *sh);

/* KM_BOOT_TRIAL_MAX new tries: after COMMIT and at START. */
void km_boot_trial_fresh(volatile km_boot_shared_t *sh);

/* Application: true if a bootloader started it. */
bool km_boot_started_by_loader(const volatile km_boot_shared_t *sh);

/* Application, once it serves the bus: this start was good. */
void km_boot_confirm(volatile km_boot_shared_t *sh);

/* Application at 0x78 ENTER (docs/update.md §3): leaves its ID and baud in
 * one word, baud / 100 in bits 16-31, ~id in 8-15, id in 0-7. */
void km_boot_handoff_set(volatile km_boot_shared_t *sh, uint8_t id, uint32_t baud);

/* Bootloader, after KM_BOOT_STAY_ASKED: the ID and baud left, if sound
 * (check byte, ID 0..250, baud 9600..1000000). */
bool km_boot_handoff_get(const volatile km_boot_shared_t *sh, uint8_t *id, uint32_t *baud);

#endif
