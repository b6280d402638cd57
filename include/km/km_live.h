/* What control reports back every tick: the live registers (PROTOCOL.md
 * §5.3), status bit 7, the protections and hardware faults, the torque
 * switch as control runs it. Shared by protocol/ and control/. */
#ifndef KM_LIVE_H
#define KM_LIVE_H

#include <stdbool.h>
#include <stdint.h>

/* Live state from control, copied in every control tick. */
typedef struct {
    int32_t position;      /* 0.1 deg, zero offsets applied */
    int32_t speed;         /* deg/s */
    int32_t current;       /* mA */
    int32_t pwm;           /* 0..1000 */
    int32_t temperature;   /* deg C */
    int32_t voltage;       /* mV */
    int32_t deviation;     /* 0.1 deg */
    uint32_t rotation_ms;  /* 0x4D */
    bool running;          /* status bit 7 */
    bool protecting;       /* a protection acts on the output: 0x64 reads 5 */
    uint8_t torque_switch; /* km_torque_t as control runs it (0x64); after a release, what it returns to */
    uint8_t protections;   /* active protections, 0x36 bits / status bits 0..3 */
    uint8_t hw_faults;     /* 0x35 bits found by the self-test (latched) */
    uint32_t time_ms;      /* ms since control started: the fault log's clock */
} km_live_t;

#endif
