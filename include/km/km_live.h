/* SPDX-License-Identifier: Apache-2.0 */
/* What control reports every tick (docs/protocol.md §5.3). */
#ifndef KM_LIVE_H
#define KM_LIVE_H

#include <stdbool.h>
#include <stdint.h>

/* One tick's changes: the fault log's input, from control alone. */
typedef struct {
    uint8_t tripped;  /* KM_PROT_* bits */
    uint8_t released; /* by themselves, or disabled by 0x32 */
    uint8_t cleared;  /* by a 0x36 clear since the last tick */
    uint8_t hw_found; /* KM_HW_* bits */
} km_protect_events_t;

/* Live state, copied every tick; byte fields first. */
typedef struct {
    bool running;          /* status bit 7 */
    bool protecting;       /* torque_switch is PROTECTED */
    bool torque_forced;    /* control set torque_switch: 0x64 shows it */
    uint8_t torque_switch; /* km_torque_t */
    uint8_t protections;   /* 0x36 bits, status bits 0..3 */
    uint8_t hw_faults;     /* 0x35 bits, latched */
    km_protect_events_t events;
    int32_t position;     /* 0.1 deg, zero offsets applied */
    int32_t speed;        /* deg/s */
    int32_t current;      /* mA */
    int32_t pwm;          /* 0..1000 */
    int32_t temperature;  /* deg C */
    int32_t voltage;      /* mV */
    int32_t deviation;    /* 0.1 deg */
    uint32_t rotation_ms; /* 0x4D */
    uint32_t time_ms;     /* since control started */
} km_live_t;

#endif
