/* Control: turns sensor readings into the live registers and the bus
 * requests into a bridge command, as step(inputs, dt) -> outputs so the host
 * tests drive it without hardware.
 *
 * This is the control *interface* and its sensing half. The motion half
 * (position loop, profiles, motor modes, protection supervisor) is a later
 * issue: until it lands, motion requests are received and counted, and the
 * bridge only ever coasts or brakes, so the plant stays where it is. */
#ifndef KM_CONTROL_H
#define KM_CONTROL_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_sensors.h"
#include "km_servo.h"

typedef enum {
    KM_BRIDGE_FREE = 0,
    KM_BRIDGE_BRAKE = 1,
    KM_BRIDGE_PWM = 2,
} km_bridge_mode_t;

typedef struct {
    km_bridge_mode_t mode;
    int16_t pwm; /* -1000..1000 when mode is PWM */
} km_bridge_t;

/* Register values control needs each tick (read from the register file). */
typedef struct {
    int16_t zero_offset1;   /* 0x16, 0.1 deg */
    int16_t zero_offset2;   /* 0x17, 0.1 deg */
    uint8_t config;         /* 0x11: bit2 direction, bit1 idle output, bit0 power-on output */
    uint8_t torque_switch;  /* 0x64 */
} km_control_config_t;

typedef struct {
    km_bridge_t bridge;
    int32_t last_position;  /* 0.1 deg, for speed */
    int32_t speed_acc;      /* 0.1 deg moved since the last speed update */
    uint32_t speed_us;      /* time accumulated for the speed estimate */
    int32_t speed_dps;
    bool have_position;
    uint32_t requests;      /* typed requests received (diagnostics) */
    km_request_t last_request;
} km_control_t;

void km_control_init(km_control_t *c, const km_control_config_t *cfg);

/* A typed request from the dispatcher. */
void km_control_request(km_control_t *c, const km_request_t *req, const km_control_config_t *cfg);

/* One control tick: sensors in, live registers and bridge command out. */
void km_control_step(km_control_t *c, const km_sensors_t *in, const km_control_config_t *cfg,
                     uint32_t dt_us, km_live_t *live, km_bridge_t *bridge);

#endif
