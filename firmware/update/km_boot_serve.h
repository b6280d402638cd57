/* SPDX-License-Identifier: Apache-2.0 */
/* The bootloader's dispatcher (docs/update.md §3, §3a, §4): ping, read
 * 0x01 and 0x0C, the standard restart and 0x78; anything else is status
 * bit 5 (docs/protocol.md §4). Pure. */
#ifndef KM_BOOT_SERVE_H
#define KM_BOOT_SERVE_H

#include <stdint.h>

#include "km_boot_trial.h"
#include "km_frame.h"
#include "km_update.h"

typedef struct {
    km_update_t upd;
    uint8_t id;                        /* the ID it answers on (stored, or the fallback 0) */
    uint8_t status;                    /* unreported status bits (bit 5) */
    uint32_t version;                  /* the 0x0C answer */
    volatile km_boot_shared_t *shared; /* the words shared with the application */
} km_boot_serve_t;

typedef enum {
    KM_BOOT_ACT_NONE = 0,
    KM_BOOT_ACT_RESTART, /* restart now (START, or the standard restart) */
} km_boot_action_t;

typedef struct {
    uint16_t len; /* 0 = no answer */
    uint8_t bytes[KM_FRAME_MAX];
    uint8_t action; /* km_boot_action_t */
} km_boot_reply_t;

/* Runs a frame to its own ID or broadcast; *r: the answer (own ID only) and action. */
void km_boot_serve(km_boot_serve_t *s, const km_frame_view_t *f, km_boot_reply_t *r);

#endif
