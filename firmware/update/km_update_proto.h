/* SPDX-License-Identifier: Apache-2.0 */
/* The 0x78 frames (docs/update.md §4): a body (sub-command first) in, the
 * answer's body out, for the bootloader and the application. Pure. */
#ifndef KM_UPDATE_PROTO_H
#define KM_UPDATE_PROTO_H

#include <stdbool.h>
#include <stdint.h>

#include "km_update.h"

#define KM_CMD_UPDATE 0x78u

#define KM_UPD_SUB_ENTER 0x01u
#define KM_UPD_SUB_BEGIN 0x02u
#define KM_UPD_SUB_WRITE 0x03u
#define KM_UPD_SUB_STATUS 0x04u
#define KM_UPD_SUB_VERIFY 0x05u
#define KM_UPD_SUB_COMMIT 0x06u
#define KM_UPD_SUB_START 0x07u

#define KM_UPD_STATUS_BITMAP_MAX 64u /* bitmap bytes per STATUS answer */
#define KM_UPD_ANSWER_MAX (9u + KM_UPD_STATUS_BITMAP_MAX)

/* What the caller does after a 0x78 frame. */
typedef enum {
    KM_UPD_ACT_NONE = 0,
    KM_UPD_ACT_EXCEPTION, /* unknown or missing sub-command: status bit 5 */
    KM_UPD_ACT_RESTART,   /* START (bootloader) */
    KM_UPD_ACT_ENTER,     /* ENTER (application): restart into update mode */
} km_update_action_t;

typedef struct {
    uint8_t len;                     /* answer body bytes; 0 = no answer */
    uint8_t body[KM_UPD_ANSWER_MAX]; /* starts with the sub-command */
    uint8_t action;                  /* km_update_action_t */
} km_update_answer_t;

/* Bootloader: runs the frame; the answer is filled whatever the ID. */
void km_update_frame(km_update_t *u, const uint8_t *body, uint8_t n, km_update_answer_t *a);

/* Application: ENTER (action ENTER, no answer) and STATUS (state 0); any
 * other sub, and ENTER with a bad magic, is bit 5. */
void km_update_app_frame(const uint8_t *body, uint8_t n, km_update_answer_t *a);

#endif
