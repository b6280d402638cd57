/* Control: one tick turns the sensors into the live registers and a bridge
 * command, as step(state, inputs, dt) so host tests drive it without
 * hardware. The app runs it every KM_CONTROL_TICK_US (1 kHz) on every
 * board, and hands it the dispatcher's typed requests.
 *
 * One tick, in order (sensing, limits and output in one place):
 *   1. sensing: position in the master's frame = (sensor + 0x16 + 0x17),
 *      negated when 0x11 bit 2 is set; speeds (km_speed_est);
 *   2. servo mode: torque switch and profile (km_servo_mode, km_profile);
 *   3. position loop (km_position_loop) when the torque is on;
 *   4. output (km_output): PWM limit 0x5B (and a move's own cap), direction
 *      back to the sensor's frame, bridge mode.
 * Motor mode (0x6E..0x70, km_motor_mode) replaces steps 2-3 while it owns
 * the bridge (hand-over rules in km_motor_mode.h). The protection
 * supervisor is a later issue. Only this header
 * and km_servo_io.h are the interface; the modules are internals. */
#ifndef KM_CONTROL_H
#define KM_CONTROL_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_sensors.h"
#include "km_output.h"
#include "km_motor_mode.h"
#include "km_position_loop.h"
#include "km_servo_io.h"
#include "km_servo_mode.h"
#include "km_speed_est.h"

#define KM_CONTROL_TICK_US 1000u /* 1 kHz: sensing, position loop and output */

typedef struct {
    km_servo_mode_t servo;
    km_motor_mode_t motor;
    km_position_loop_t loop;
    km_speed_window_t speed;     /* 0x47 */
    km_speed_fast_t fast;        /* the loop's damping input */
    km_bridge_t bridge;          /* the last command */
    int32_t position;            /* 0.1 deg, master's frame, last tick */
    bool have_position;
    int32_t temp_c10;            /* the last temperature read, 0.1 degC, */
    int32_t temp_c;              /* and it in degC: divided again only when it changes */
    uint32_t requests;           /* typed requests received (diagnostics) */
    km_request_t last_request;
} km_control_t;

void km_control_init(km_control_t *c, const km_control_params_t *p);

/* A typed request from the dispatcher; false = refused (status bit 6). */
bool km_control_request(km_control_t *c, const km_request_t *req, const km_control_params_t *p);

/* One control tick: sensors in, live registers and bridge command out. */
void km_control_step(km_control_t *c, const km_sensors_t *in, const km_control_params_t *p,
                     uint32_t dt_us, km_live_t *live, km_bridge_t *bridge);

#endif
