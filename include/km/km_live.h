/* SPDX-License-Identifier: Apache-2.0 */
/* What control reports back every tick: the live registers (docs/protocol.md
 * §5.3), status bit 7, the protections and hardware faults, the torque
 * switch as control runs it. Shared by protocol/ and control/. */
#ifndef KM_LIVE_H
#define KM_LIVE_H

#include <stdbool.h>
#include <stdint.h>

/* What changed at one control tick: the fault log's input (the app writes
 * it, firmware/app/km_fault_log.h). Control is the one source: its
 * supervisor and self-test report what they did, nothing re-derives it. */
typedef struct {
    uint8_t tripped;  /* protections that tripped (KM_PROT_* bits) */
    uint8_t released; /* protections released by themselves (automatic release, or disabled by 0x32) */
    uint8_t cleared;  /* protections released by a clear request (0x36 write) since the last tick */
    uint8_t hw_found; /* hardware faults found (KM_HW_* bits) */
} km_protect_events_t;

/* Live state from control, copied in every control tick; byte fields first. */
typedef struct {
    bool running;               /* status bit 7 */
    bool protecting;            /* a protection acts on the output (torque_switch is PROTECTED) */
    bool torque_forced;         /* control set the torque switch itself this tick: 0x64 shows torque_switch */
    uint8_t torque_switch;      /* km_torque_t as control runs it */
    uint8_t protections;        /* active protections, 0x36 bits / status bits 0..3 */
    uint8_t hw_faults;          /* 0x35 bits found by the self-test (latched) */
    km_protect_events_t events; /* what changed at this tick */
    int32_t position;           /* 0.1 deg, zero offsets applied */
    int32_t speed;              /* deg/s */
    int32_t current;            /* mA */
    int32_t pwm;                /* 0..1000 */
    int32_t temperature;        /* deg C */
    int32_t voltage;            /* mV */
    int32_t deviation;          /* 0.1 deg */
    uint32_t rotation_ms;       /* 0x4D */
    uint32_t time_ms;           /* ms since control started: the fault log's clock */
} km_live_t;

#endif
