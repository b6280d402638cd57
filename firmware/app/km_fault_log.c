/* SPDX-License-Identifier: Apache-2.0 */
/* Fault log: a ring of the last events in RAM a reset keeps (km_fault_log.h). */
#include "km_fault_log.h"

#include <string.h>

#define PRV_MAGIC 0x4B4D464Cu /* "KMFL" */

/* A rotate-xor over the bytes before `check`. */
static uint32_t prv_check(const km_fault_log_t *log)
{
    const uint8_t *b = (const uint8_t *)log;
    const size_t n = offsetof(km_fault_log_t, check);
    uint32_t sum = 0x9E3779B9u;
    for (size_t i = 0; i < n; i++) {
        sum = ((sum << 5) | (sum >> 27)) ^ b[i];
    }
    return sum;
}

static bool prv_valid(const km_fault_log_t *log)
{
    return log->magic == PRV_MAGIC && log->held <= KM_FAULT_LOG_LEN && log->head < KM_FAULT_LOG_LEN &&
           log->kept <= log->held && log->check == prv_check(log);
}

bool km_fault_log_boot(km_fault_log_t *log)
{
    const bool keep = prv_valid(log);
    if (!keep) {
        memset(log, 0, sizeof *log);
        log->magic = PRV_MAGIC;
    } else {
        for (uint8_t i = 0; i < KM_FAULT_LOG_LEN; i++) {
            if (log->entries[i].boots_ago < UINT8_MAX) {
                log->entries[i].boots_ago++;
            }
        }
        log->kept = log->held;
    }
    log->check = prv_check(log);
    return keep;
}

void km_fault_log_add(km_fault_log_t *log, const km_fault_entry_t *e)
{
    /* invalidate first: a torn update starts empty */
    log->check = ~log->check;
    log->entries[log->head] = *e;
    log->entries[log->head].boots_ago = 0;
    log->entries[log->head].reserved = 0;
    log->head = (uint8_t)((log->head + 1u) % KM_FAULT_LOG_LEN);
    if (log->held < KM_FAULT_LOG_LEN) {
        log->held++;
    } else if (log->kept > 0u) {
        log->kept--; /* the oldest, dropped, was a kept one */
    }
    log->total++;
    log->check = prv_check(log);
}

/* One entry of `kind` with the live state it happened in. */
static void prv_add_event(km_fault_log_t *log, const km_live_t *live, km_fault_kind_t kind, uint8_t bits)
{
    if (bits == 0u) {
        return;
    }
    km_fault_entry_t e;
    e.t_ms = live->time_ms;
    e.position = live->position;
    e.voltage_mv = (uint16_t)(live->voltage < 0 ? 0 : live->voltage > 65535 ? 65535 : live->voltage);
    e.current_ma = (int16_t)(live->current < -32768 ? -32768 : live->current > 32767 ? 32767 : live->current);
    e.temp_c10 = (int16_t)(live->temperature * 10);
    e.kind = (uint8_t)kind;
    e.bits = bits;
    e.boots_ago = 0;
    e.reserved = 0;
    km_fault_log_add(log, &e);
}

void km_fault_log_record(km_fault_log_t *log, const km_live_t *live)
{
    const km_protect_events_t *ev = &live->events;
    if ((ev->tripped | ev->cleared | ev->released | ev->hw_found) == 0u) {
        return; /* the usual tick */
    }
    prv_add_event(log, live, KM_FAULT_EV_TRIP, ev->tripped);
    prv_add_event(log, live, KM_FAULT_EV_CLEAR, ev->cleared);
    prv_add_event(log, live, KM_FAULT_EV_RELEASE, ev->released);
    prv_add_event(log, live, KM_FAULT_EV_HW, ev->hw_found);
}

bool km_fault_log_get(const km_fault_log_t *log, uint8_t n, km_fault_entry_t *out)
{
    if (n >= log->held) {
        return false;
    }
    const uint8_t slot = (uint8_t)((log->head + KM_FAULT_LOG_LEN - 1u - n) % KM_FAULT_LOG_LEN);
    *out = log->entries[slot];
    return true;
}

static size_t prv_put(uint8_t *out, uint32_t v, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        out[i] = (uint8_t)(v >> (8u * i));
    }
    return n;
}

size_t km_fault_log_summary(const km_fault_log_t *log, uint8_t *out)
{
    size_t n = prv_put(out, log->total, 4);
    out[n++] = log->held;
    out[n++] = log->kept;
    out[n++] = (uint8_t)KM_FAULT_LOG_LEN;
    return n;
}

size_t km_fault_log_entry_bytes(const km_fault_entry_t *e, uint8_t *out)
{
    size_t n = prv_put(out, e->t_ms, 4);
    out[n++] = e->kind;
    out[n++] = e->bits;
    out[n++] = e->boots_ago;
    out[n++] = 0;
    n += prv_put(&out[n], e->voltage_mv, 2);
    n += prv_put(&out[n], (uint16_t)e->current_ma, 2);
    n += prv_put(&out[n], (uint16_t)e->temp_c10, 2);
    n += prv_put(&out[n], (uint32_t)e->position, 4);
    return n;
}
