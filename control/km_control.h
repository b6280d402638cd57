/* SPDX-License-Identifier: Apache-2.0 */
/* Control: one tick turns the sensors into the live registers and a bridge
 * command, as step(state, inputs, dt) so host tests drive it without
 * hardware. The app runs it every KM_CONTROL_TICK_US (1 kHz) on every
 * board, and hands it the dispatcher's typed requests.
 *
 * One tick, in order (sensing, limits and output in one place):
 *   1. sensing: position in the master's frame = (sensor + 0x16 + 0x17),
 *      negated when 0x11 bit 2 is set; speeds (km_speed_est);
 *   2. self-test (km_selftest: 0x35 over the first ticks, the motor lead
 *      whenever driven) and protection supervisor (km_protect: 0x32-0x3F),
 *      on the sensors and the PWM the bridge drives now; a new hardware
 *      fault or protection stops motion here;
 *   3. servo mode: torque switch and profile (km_servo_mode, km_profile),
 *      position loop (km_position_loop) when the torque is on;
 *   4. output (km_output): PWM limit min(0x5B, 0x13, a move's own cap, the
 *      current limit's cap: km_current_limit, 0x5C/0x14), direction back
 *      to the sensor's frame, bridge mode; then the protection's action
 *      (free, brake, or hold = servo mode holding where it tripped), so
 *      nothing reaches the bridge without passing the supervisor.
 * Motor mode (0x6E..0x70, km_motor_mode) replaces step 3 while it owns
 * the bridge (hand-over rules in km_motor_mode.h).
 * A change of the master's frame (0x17, 0x18, 0x46 zeroing, 0x11 bit 2)
 * is rebased before step 1: the held target, a move's set-point, a run's
 * start and the speed estimates follow it, so the shaft does not move (a
 * move in progress ends at its set-point of that tick).
 *
 * While protecting, 0x64 reads 5; motion requests and 0x64 = 2/3 are
 * refused (status bit 6); a request for less motion (km_request.h) is
 * always taken, here and with a hardware fault latched: 0x64 = 0/1 (the
 * output is off anyway) are what 0x64 returns to, a motor stop (0x6E/0x6F
 * = 0, 0x70 stop) leaves motor mode stopped, and ends a hold action's
 * hold. On release 0x64 returns to 0/1 if it was
 * off, to 2 if the output held position throughout (a hold action), else
 * to 3 (armed: on at the next rotation command, so a released servo never
 * moves by itself). Only this header
 * and the shared types of include/km/ are the interface; the modules are
 * internals. */
#ifndef KM_CONTROL_H
#define KM_CONTROL_H

#include <stdbool.h>
#include <stdint.h>

#include "km_current_limit.h"
#include "km_axis.h"
#include "km_hal_sensors.h"
#include "km_output.h"
#include "km_motor_mode.h"
#include "km_position_loop.h"
#include "km_protect.h"
#include "km_selftest.h"
#include "km_live.h"
#include "km_params.h"
#include "km_request.h"
#include "km_servo_mode.h"
#include "km_speed_est.h"

#define KM_CONTROL_TICK_US 1000u /* 1 kHz: sensing, position loop and output */

typedef struct {
    /* The tick's own scalars first: on the M0 a byte load or store reaches
     * 32 bytes into a struct, a word one 128. */
    uint8_t action;   /* km_prot_action_t in force */
    uint8_t ts_after; /* 0x64 once the protections are released */
    uint8_t hw;       /* 0x35 bits found */
    uint8_t cleared;  /* protections a clear request released since the last tick */
    bool have_position;
    km_axis_t frame;    /* the master's frame of the last tick (km_axis.h) */
    km_bridge_t bridge; /* the last command */
    int32_t position;   /* 0.1 deg, master's frame, last tick */
    int32_t temp_c10;   /* the last temperature read, 0.1 degC, */
    int32_t temp_c;     /* and it in degC: divided again only when it changes */
    uint32_t time_ms;   /* since init (the fault log's clock) */
    uint32_t time_rem_us;
    km_servo_mode_t servo;
    km_motor_mode_t motor;
    km_position_loop_t loop;
    km_speed_window_t speed; /* 0x47 */
    km_speed_fast_t fast;    /* the loop's damping input */
    km_hold_filter_t hold;   /* the position while holding still */
    km_current_limit_t ilim; /* 0x5C / 0x14 */
    km_protect_t prot;       /* the protection supervisor */
    km_selftest_t selftest;  /* 0x35 */
    uint32_t requests;       /* typed requests received (diagnostics) */
    km_request_t last_request;
} km_control_t;

void km_control_init(km_control_t *c, const km_control_params_t *p);

/* A typed request from the dispatcher; false = refused (status bit 6). */
bool km_control_request(km_control_t *c, const km_request_t *req, const km_control_params_t *p);

/* One control tick: sensors in, live registers and bridge command out. */
void km_control_step(km_control_t *c, const km_sensors_t *in, const km_control_params_t *p, uint32_t dt_us,
                     km_live_t *live, km_bridge_t *bridge);

#endif
