/* SPDX-License-Identifier: Apache-2.0 */
/* Host fixture: control (control/km_control.h) stepped against the servo
 * plant (sim/plant) directly, no hal, at the 1 kHz control tick, with the
 * bridge command of one tick applied to the plant during the next one (a
 * one-tick PWM delay, as on a board whose PWM updates at the next period).
 *
 * Params start as the simulated product (boards/sim-common/km_sim_product.c)
 * decodes them at power-on: 0x11 = 0x02, travel and angle limits +-135.0 deg,
 * position readings +-157.5 deg at most,
 * 0x13 = 0x5B = 1000, 0x15 = 0x5D = 360 deg/s, 0x64 = 3 (armed), default
 * gains. Header-only (tests/support/ is on the include path); include after
 * cmocka's headers. */
#ifndef KM_PLANT_RIG_H
#define KM_PLANT_RIG_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "km_control.h"
#include "km_plant.h"

typedef struct {
    km_plant_t plant;
    km_control_t ctl;
    km_control_params_t params;
    km_plant_input_t in; /* the command the plant runs during the next tick */
    km_live_t live;
    km_bridge_t bridge;
    uint32_t t_ms; /* ticks since kr_init */
    bool encoder;  /* position from the multi-turn reading */
} kr_rig_t;

static inline void kr_default_params(km_control_params_t *p)
{
    const km_control_gains_t g = KM_CONTROL_GAINS_DEFAULT;
    memset(p, 0, sizeof *p);
    p->variant = KM_VARIANT_POTENTIOMETER;
    p->idle_brake = true;
    p->max_torque = 1000;
    p->max_current_ma = 2000;
    p->max_speed_dps = 360;
    p->angle_min = -1350;
    p->angle_max = 1350;
    p->travel_min = -1350;
    p->travel_max = 1350;
    p->pos_read_min = -1575; /* the plant's stops +-150.0 deg, and a tolerance */
    p->pos_read_max = 1575;
    p->torque_limit = 1000;
    p->current_limit_ma = 2000;
    p->speed_limit_dps = 360;
    p->torque_switch = 3;
    p->gains = g;
}

static inline void kr_sensors(const kr_rig_t *r, km_sensors_t *s)
{
    memset(s, 0, sizeof *s);
    s->position = r->encoder ? km_plant_turns_ddeg(&r->plant) : km_plant_position_ddeg(&r->plant);
    s->current_ma = km_plant_current_ma(&r->plant);
    s->voltage_mv = km_plant_voltage_mv(&r->plant);
    s->temperature_c10 = km_plant_temp_dc(&r->plant);
}

/* One 1 ms tick: the plant runs the previous command, control reads it. */
static inline void kr_tick(kr_rig_t *r)
{
    km_plant_step(&r->plant, &r->in, KM_CONTROL_TICK_US);
    km_sensors_t s;
    kr_sensors(r, &s);
    km_control_step(&r->ctl, &s, &r->params, KM_CONTROL_TICK_US, &r->live, &r->bridge);
    r->in.bridge = r->bridge.mode == KM_BRIDGE_PWM     ? KM_PLANT_DRIVE
                   : r->bridge.mode == KM_BRIDGE_BRAKE ? KM_PLANT_BRAKE
                                                       : KM_PLANT_COAST;
    r->in.pwm = r->bridge.mode == KM_BRIDGE_PWM ? r->bridge.pwm : 0;
    r->t_ms++;
}

static inline void kr_run(kr_rig_t *r, uint32_t ms)
{
    for (uint32_t i = 0; i < ms; i++) {
        kr_tick(r);
    }
}

/* Plant at rest at `pos_ddeg` (sensor frame), params at the defaults,
 * control initialised and one tick run (the first sample). */
static inline void kr_init_at(kr_rig_t *r, const km_plant_config_t *pc, int32_t pos_ddeg)
{
    memset(r, 0, sizeof *r);
    (void)km_plant_init(&r->plant, pc);
    km_plant_set_position_ddeg(&r->plant, pos_ddeg);
    kr_default_params(&r->params);
    km_control_init(&r->ctl, &r->params);
    r->in.bridge = KM_PLANT_COAST;
    kr_tick(r);
}

static inline void kr_init(kr_rig_t *r)
{
    kr_init_at(r, &km_plant_default_config, 0);
}

/* The encoder product on `base` without pot or end stops (a free multi-turn
 * shaft), at rest at `pos_ddeg`: position from the turn count, the encoder
 * variant, no travel and no angle limits. `cfg` is the caller's static: the
 * plant keeps a pointer to it. */
static inline void kr_init_encoder_at(kr_rig_t *r, km_plant_config_t *cfg, const km_plant_config_t *base,
                                      int32_t pos_ddeg)
{
    *cfg = *base;
    cfg->pot_travel_ddeg = 0;
    cfg->endstop_ddeg = 0;
    kr_init_at(r, cfg, pos_ddeg);
    r->encoder = true;
    r->params.variant = KM_VARIANT_ENCODER;
    r->params.travel_min = INT16_MIN;
    r->params.travel_max = INT16_MAX;
    r->params.angle_min = 0;
    r->params.angle_max = 0;
}

static inline bool kr_request(kr_rig_t *r, const km_request_t *req)
{
    return km_control_request(&r->ctl, req, &r->params);
}

static inline bool kr_torque(kr_rig_t *r, uint8_t v)
{
    km_request_t q;
    memset(&q, 0, sizeof q);
    q.kind = KM_REQ_TORQUE;
    q.u.torque = v;
    if (!kr_request(r, &q)) {
        return false;
    }
    r->params.torque_switch = v; /* as the dispatcher stores it */
    return true;
}

/* A move as the dispatcher's hooks decode one: `kind` KM_MOVE_*, `param`
 * the time (ms) or speed (deg/s), 0 = fastest; no PWM cap. */
static inline bool kr_move_full(kr_rig_t *r, km_move_kind_t kind, bool relative, int16_t target,
                                uint16_t param, uint16_t pwm_cap)
{
    km_request_t q;
    memset(&q, 0, sizeof q);
    q.kind = KM_REQ_MOVE;
    q.u.move.kind = (uint8_t)kind;
    q.u.move.relative = relative;
    q.u.move.target = target;
    q.u.move.time_or_speed = param;
    q.u.move.pwm_cap = pwm_cap;
    return kr_request(r, &q);
}

/* An absolute move (0x65 time, 0x66 speed, 0x68 stream). */
static inline bool kr_move(kr_rig_t *r, km_move_kind_t kind, int16_t target, uint16_t param)
{
    return kr_move_full(r, kind, false, target, param, 1000u);
}

/* A relative move (0x67 high nibble 1): `delta` from the target in force. */
static inline bool kr_move_rel(kr_rig_t *r, km_move_kind_t kind, int16_t delta, uint16_t param)
{
    return kr_move_full(r, kind, true, delta, param, 1000u);
}

/* A fastest move under a PWM cap (0x67 low nibble 2). */
static inline bool kr_move_capped(kr_rig_t *r, int16_t target, uint16_t pwm_cap)
{
    return kr_move_full(r, KM_MOVE_SPEED, false, target, 0u, pwm_cap);
}

/* A motor run as the dispatcher's hooks decode 0x6E..0x70. */
static inline bool kr_run_motor(kr_rig_t *r, km_run_mode_t mode, bool reverse, uint16_t value,
                                km_run_until_t until, uint16_t amount, km_run_after_t after)
{
    km_request_t q;
    memset(&q, 0, sizeof q);
    q.kind = KM_REQ_MOTOR;
    q.u.run.mode = (uint8_t)mode;
    q.u.run.reverse = reverse;
    q.u.run.value = value;
    q.u.run.until = (uint8_t)until;
    q.u.run.amount = amount;
    q.u.run.after = (uint8_t)after;
    return kr_request(r, &q);
}

/* 0x6E (PWM) or 0x6F (speed): a signed value, run on, idle output at 0. */
static inline bool kr_motor_signed(kr_rig_t *r, km_run_mode_t mode, int16_t v)
{
    const uint16_t mag = (uint16_t)(v < 0 ? -(int32_t)v : (int32_t)v);
    return kr_run_motor(r, mode, v < 0, mag, KM_UNTIL_NONE, 0u, KM_AFTER_IDLE);
}

/* Reported position (0x46), 0.1 deg. */
static inline int32_t kr_pos(const kr_rig_t *r)
{
    return r->live.position;
}

#endif
