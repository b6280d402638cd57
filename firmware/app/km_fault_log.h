/* SPDX-License-Identifier: Apache-2.0 */
/* Fault log (beyond the spec): the last KM_FAULT_LOG_LEN protection and
 * self-test events with when, what and the live state, written from the
 * events control reports and read through 0x7F. Plain RAM kept across
 * resets, guarded by a magic and a check word (docs/protocol-decisions.md
 * "Fault log", docs/app-design.md). */
#ifndef KM_FAULT_LOG_H
#define KM_FAULT_LOG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "km_live.h"

#define KM_FAULT_LOG_LEN 16u
#define KM_FAULT_ENTRY_SIZE 18u /* bytes of one entry on the wire */

typedef enum {
    KM_FAULT_EV_TRIP = 1,    /* protections tripped (0x36 bits) */
    KM_FAULT_EV_RELEASE = 2, /* released by themselves (automatic, or disabled) */
    KM_FAULT_EV_CLEAR = 3,   /* released by a 0x36 write */
    KM_FAULT_EV_HW = 4,      /* hardware faults found (0x35 bits) */
} km_fault_kind_t;

typedef struct {
    uint32_t t_ms;    /* ms since the boot it happened in */
    int32_t position; /* 0.1 deg, as 0x46 */
    uint16_t voltage_mv;
    int16_t current_ma;
    int16_t temp_c10;  /* 0.1 degC */
    uint8_t kind;      /* km_fault_kind_t */
    uint8_t bits;      /* 0x36 bits (protections) or 0x35 bits (hardware) */
    uint8_t boots_ago; /* 0 = this boot, 1 = the boot before the last reset, ... (saturates) */
    uint8_t reserved;
} km_fault_entry_t;

typedef struct {
    uint32_t magic;
    uint32_t total; /* entries ever added to this log (wraps) */
    uint8_t head;   /* the slot the next entry goes to */
    uint8_t held;   /* entries held, <= KM_FAULT_LOG_LEN */
    uint8_t kept;   /* of them, from before the last reset */
    uint8_t reserved;
    km_fault_entry_t entries[KM_FAULT_LOG_LEN];
    uint32_t check; /* over everything above */
} km_fault_log_t;

/* At boot: keeps a log that checks (one boot older), else starts empty. */
bool km_fault_log_boot(km_fault_log_t *log);

/* Adds an event (the oldest is dropped when full). */
void km_fault_log_add(km_fault_log_t *log, const km_fault_entry_t *e);

/* One entry per kind of event in live->events, with that tick's live state. */
void km_fault_log_record(km_fault_log_t *log, const km_live_t *live);

/* Entry `n`, 0 = the newest; false if there are not that many. */
bool km_fault_log_get(const km_fault_log_t *log, uint8_t n, km_fault_entry_t *out);

/* Wire forms for 0x7F: summary (u32 total, u8 held, u8 kept, u8 length)
 * and entry (docs/protocol-decisions.md "Fault log"); bytes written. */
#define KM_FAULT_SUMMARY_SIZE 7u
size_t km_fault_log_summary(const km_fault_log_t *log, uint8_t *out);
size_t km_fault_log_entry_bytes(const km_fault_entry_t *e, uint8_t *out);

#endif
