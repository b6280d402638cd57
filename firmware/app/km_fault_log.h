/* SPDX-License-Identifier: Apache-2.0 */
/* Fault log (beyond the spec: a servo that shut down in the field must say
 * why): the last KM_FAULT_LOG_LEN protection and self-test events, each with
 * when (ms since its boot, and which boot), what (trip, release, clear,
 * hardware fault, which bits) and the live state at that moment (supply,
 * current, temperature, position). Pure. Written from the events control
 * reports with its live values (km_fault_log_record: control is the one
 * source of what tripped, released, was cleared or found), read over the
 * bus through the extension command 0x7F, which the app serves from here
 * (docs/protocol-decisions.md "Fault log").
 *
 * Kept across restarts, not across power loss: the log is plain RAM that
 * the board places where a reset does not clear it (.noinit on the MCU
 * boards), guarded by a magic and a check word; at boot a log that checks
 * is kept (its entries marked one boot older), anything else starts empty.
 * So a 0x02 restart, a watchdog or a fault reset keeps the record of what
 * led to it, and normal operation never costs a flash erase or program. */
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

/* At boot, on the log's RAM as the reset left it: keeps a log that checks
 * (one boot older), else starts an empty one. Returns true if kept. */
bool km_fault_log_boot(km_fault_log_t *log);

/* Adds an event (the oldest is dropped when full). */
void km_fault_log_add(km_fault_log_t *log, const km_fault_entry_t *e);

/* The events of one control tick (live->events), each kind that happened
 * as one entry with the live state of that tick: trips, clears, releases,
 * hardware faults, in that order. Nothing for a tick without events. */
void km_fault_log_record(km_fault_log_t *log, const km_live_t *live);

/* Entry `n`, 0 = the newest; false if there are not that many. */
bool km_fault_log_get(const km_fault_log_t *log, uint8_t n, km_fault_entry_t *out);

/* Wire forms for 0x7F (little-endian):
 *   summary (7 B): u32 total, u8 held, u8 kept, u8 KM_FAULT_LOG_LEN;
 *   entry (18 B):  u32 t_ms, u8 kind, u8 bits, u8 boots_ago, u8 0,
 *                  u16 voltage mV, i16 current mA, i16 temperature 0.1 degC,
 *                  i32 position 0.1 deg.
 * Each returns the bytes written (out holds at least that many). */
#define KM_FAULT_SUMMARY_SIZE 7u
size_t km_fault_log_summary(const km_fault_log_t *log, uint8_t *out);
size_t km_fault_log_entry_bytes(const km_fault_entry_t *e, uint8_t *out);

#endif
