/* SPDX-License-Identifier: Apache-2.0 */
/* Control: every KM_CONTROL_TICK_US the sensors become the live registers
 * and a bridge command (sensing, self-test and protection, servo or motor
 * mode, output), and the dispatcher's typed requests are taken or refused.
 * This header and include/km/ are the interface. The tick and the rules
 * while protecting: docs/control-design.md "The tick". */
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

/* A 0x68 stream's loop on the sub-count observer (1, the default) or on
 * the counts and the fast speed as a move's (0: the 32 KiB STM32G031F6
 * build, docs/footprint.md "What gives way"). */
#ifndef KM_FEATURE_STREAM_OBS
#define KM_FEATURE_STREAM_OBS 1
#endif

typedef struct {
    /* Byte scalars first: an M0 byte access reaches 32 bytes into a struct. */
    uint8_t action;   /* km_prot_action_t in force */
    uint8_t ts_after; /* 0x64 once the protections are released */
    uint8_t hw;       /* 0x35 bits found */
    uint8_t cleared;  /* protections a clear request released since the last tick */
    bool have_position;
    bool obs_on;        /* the observer below runs (a stream) */
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
    km_speed_obs_t obs;      /* position and speed between counts (a 0x68 stream's loop input) */
    int32_t obs_ddps;        /* its speed this tick */
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
