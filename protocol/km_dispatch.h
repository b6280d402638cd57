/* SPDX-License-Identifier: Apache-2.0 */
/* The commands of the dispatcher's table (inside protocol/ only) and what they share. */
#ifndef KM_DISPATCH_H
#define KM_DISPATCH_H

#include <stdint.h>

#include "km_frame.h"
#include "km_servo.h"

/* How an answer dealt with bits 5/6 ("Status bits 5 and 6"). */
typedef enum {
    KM_REPORT_NONE, /* no answer: this command's bits wait for a status answer */
    KM_REPORT_OWN,  /* the answer carried this command's bits (or had no status byte) */
    KM_REPORT_ALL,  /* the answer carried every unreported bit: they are cleared */
} km_report_t;

typedef km_report_t (*km_command_fn)(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply);

/* §3 commands (km_servo.c, km_cmd_multi.c, km_ext.c, km_cmd_update.c). */
km_report_t km_cmd_ping(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply);
km_report_t km_cmd_read(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply);
km_report_t km_cmd_write(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply);
km_report_t km_cmd_sync_write(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply);
km_report_t km_cmd_sync_execute(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply);
#if KM_FEATURE_MULTI_READ
km_report_t km_cmd_multi_read(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply);
#endif
km_report_t km_cmd_multi_write(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply);
km_report_t km_cmd_ext(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply);
km_report_t km_cmd_update(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply);

/* A write of `len` bytes to `addr` (0x03, 0x84, an 0x83 entry): the
 * register's write hook, or bit 5 for an address nobody may write. */
void km_dispatch_write(km_servo_t *s, uint8_t addr, const uint8_t *d, uint8_t len);

/* The readable register at `addr`, or -1 (unknown, or write-only). */
int km_dispatch_readable(uint8_t addr);

/* The answer to a read of register r (-1: bit 5, short response), started in slot `slot`; reply NULL: the
 * read runs (bit 5, the register's read) with nothing encoded. */
void km_dispatch_read_answer(km_servo_t *s, int r, uint8_t addr, uint32_t slot, km_reply_t *reply);

/* The answer's start after the frame: 0x12, plus the own ID's slot when
 * the frame went to the super ID; slots cut for `max_answer_bytes`. */
uint32_t km_dispatch_delay_us(const km_servo_t *s, uint8_t frame_id, uint16_t max_answer_bytes);

/* The short response with `status`, timed as km_dispatch_delay_us(). */
void km_dispatch_answer_status(km_servo_t *s, uint8_t status, uint8_t frame_id, km_reply_t *reply);

#endif
