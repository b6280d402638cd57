/* SPDX-License-Identifier: Apache-2.0 */
/* Servo mode: torque switch state machine and rotation commands (see
 * km_servo_mode.h for the rules). */
#include "km_servo_mode.h"

#include <string.h>

#include "km_fixdiv.h"
#include "km_axis.h"

void km_servo_mode_init(km_servo_mode_t *m, const km_control_params_t *p)
{
    memset(m, 0, sizeof *m);
    m->ts = p->torque_switch;
    m->pwm_cap = 1000;
    km_profile_reset(&m->profile, 0);
}

int32_t km_servo_mode_clamp(const km_control_params_t *p, int32_t t)
{
    int32_t lo = INT32_MIN, hi = INT32_MAX; /* multi-turn: no edge, any turn count */
    if (km_params_variant(p) != KM_VARIANT_ENCODER) {
        km_axis_travel(p, &lo, &hi); /* the travel moves with the zero offsets */
    }
    if (p->angle_min != 0 && p->angle_min > lo) {
        lo = p->angle_min;
    }
    if (p->angle_max != 0 && p->angle_max < hi) {
        hi = p->angle_max;
    }
    if (lo > hi) {
        return t; /* no valid range (cannot happen: the dispatcher keeps min < max) */
    }
    return t < lo ? lo : (t > hi ? hi : t);
}

/* Speed limit in profile units: 0x5D, never above the product's fastest
 * (the speed its motor still follows with a margin: docs/tuning.md). */
static int32_t prv_vlimit(const km_control_params_t *p)
{
    const uint32_t fastest = p->gains.fastest_dps;
    uint32_t dps = p->speed_limit_dps ? p->speed_limit_dps : fastest;
    if (fastest != 0u && dps > fastest) {
        dps = fastest;
    }
    return (int32_t)(dps ? dps : 1u) * KM_PROFILE_UPS_PER_DPS;
}

static int32_t prv_accel(const km_control_params_t *p)
{
    const uint32_t a = p->gains.accel_dps2 ? p->gains.accel_dps2 : 1u;
    return (int32_t)(a > 100000u ? 100000u : a) * 10; /* deg/s^2 -> u/s per ms */
}

static void prv_stop(km_servo_mode_t *m, uint8_t ts)
{
    m->ts = ts;
    m->running = false;
    m->streaming = false;
    m->touched = true;
}

/* Turns the torque on holding `position`. */
static KM_COMPACT_NOINLINE void prv_on_at(km_servo_mode_t *m, int32_t position)
{
    km_profile_reset(&m->profile, position);
    m->target = position;
    m->ts = KM_TORQUE_ON;
    m->pwm_cap = 1000;
    m->reset_loop = true;
    m->touched = true;
}

/* Speed for a speed parameter in deg/s (0 = fastest), in profile units. */
static int32_t prv_speed(const km_control_params_t *p, uint32_t dps)
{
    const int32_t lim = prv_vlimit(p);
    if (dps == 0u) {
        return lim;
    }
    const int32_t v = (int32_t)dps * KM_PROFILE_UPS_PER_DPS;
    return v < lim ? v : lim;
}

bool km_servo_mode_torque(km_servo_mode_t *m, km_torque_t torque, int32_t position)
{
    switch (torque) {
    case KM_TORQUE_ON:
        if (m->ts == KM_TORQUE_PROTECTED) {
            return false; /* a protection holds the output until released */
        }
        if (m->ts != KM_TORQUE_ON) {
            prv_on_at(m, position); /* hold the current position */
        }
        return true;
    case KM_TORQUE_FREE:
    case KM_TORQUE_BRAKE:
    case KM_TORQUE_ARMED:
        prv_stop(m, (uint8_t)torque);
        return true;
    default:
        return false;
    }
}

/* Starts the profile toward `target` (clamped) the way the move asks. */
static KM_COMPACT_NOINLINE void prv_plan(km_servo_mode_t *m, const km_move_t *mv,
                                         const km_control_params_t *p, int32_t target, bool was_on)
{
    const int32_t vlim = prv_vlimit(p);
    switch (mv->kind) {
    case KM_MOVE_TIME:
        if (mv->time_or_speed == 0u) {
            km_profile_move(&m->profile, target, vlim, prv_accel(p));
        } else {
            km_profile_retime(&m->profile, target, mv->time_or_speed, vlim, prv_accel(p));
        }
        return;
    case KM_MOVE_SPEED:
        km_profile_move(&m->profile, target, prv_speed(p, mv->time_or_speed), prv_accel(p));
        return;
    default: /* KM_MOVE_STREAM */
        if (was_on && m->streaming && m->stream_us <= KM_STREAM_GAP_US) {
            km_profile_stream(&m->profile, target, m->stream_us, vlim,
                              prv_accel(p) / KM_PROFILE_STREAM_ACCEL_DIV);
        } else {
            km_profile_move(&m->profile, target, vlim, prv_accel(p)); /* no rate to pace by yet: fastest */
        }
        return;
    }
}

KM_COMPACT_NOINLINE bool km_servo_mode_move(km_servo_mode_t *m, const km_move_t *mv,
                                            const km_control_params_t *p, int32_t position)
{
    if (m->ts != KM_TORQUE_ON && m->ts != KM_TORQUE_ARMED) {
        return false; /* torque off or protecting */
    }
    const bool was_on = m->ts == KM_TORQUE_ON;
    if (!was_on) {
        prv_on_at(m, position); /* armed: on at the next move */
    }
    /* relative: from the target in force (or the position if just on) */
    const int32_t target = km_profile_reach(
        &m->profile, km_servo_mode_clamp(p, mv->relative ? km_pos_add(m->target, mv->target) : mv->target));
    prv_plan(m, mv, p, target, was_on);
    m->pwm_cap = mv->pwm_cap > 1000u ? 1000 : (int32_t)mv->pwm_cap;
    m->streaming = mv->kind == KM_MOVE_STREAM;
    m->stream_us = 0;
    m->target = target;
    m->running = true;
    m->rotation_ms = 0;
    m->rotation_rem_us = 0;
    m->settle_us = 0;
    return true;
}

KM_COMPACT_NOINLINE void km_servo_mode_rebase(km_servo_mode_t *m, int32_t position)
{
    km_profile_reset(&m->profile, position);
    m->target = position;
    m->running = false;
    m->streaming = false;
    m->reset_loop = true;
}

void km_servo_mode_protect(km_servo_mode_t *m)
{
    prv_stop(m, KM_TORQUE_PROTECTED);
}

int32_t km_servo_mode_deviation(const km_servo_mode_t *m, int32_t position)
{
    return m->ts == KM_TORQUE_ON ? km_pos_diff(position, m->target) : 0;
}

/* The blocked-shaft clock: runs while the shaft stays within the arrive
 * band of where it last was, restarts whenever it moved further (a shaft
 * still on its way is not blocked). */
static void prv_settle_clock(km_servo_mode_t *m, const km_control_params_t *p, int32_t position,
                             uint32_t dt_us)
{
    const int32_t moved = km_pos_diff(position, m->settle_pos);
    const int32_t band = (int32_t)p->gains.arrive_ddeg;
    if (m->settle_us == 0u || moved > band || moved < -band) {
        m->settle_pos = position;
        m->settle_us = 0u;
    }
    m->settle_us += dt_us;
}

/* 0x4D's clock: whole ms of the motion, the rest carried (a subtraction
 * at the 1 kHz tick, a divide only after a late one). */
static void prv_count_rotation(km_servo_mode_t *m, uint32_t dt_us)
{
    uint32_t rem = m->rotation_rem_us + dt_us;
    const uint32_t ms = rem < 2000u ? (rem >= 1000u ? 1u : 0u) : km_udiv1000(rem);
    m->rotation_ms += ms;
    m->rotation_rem_us = rem - ms * 1000u;
}

void km_servo_mode_step(km_servo_mode_t *m, const km_control_params_t *p, int32_t position,
                        int32_t speed_ddps, uint32_t dt_us, km_servo_mode_out_t *out)
{
    /* every field assigned below (no memset: a byte loop on the M0) */
    out->pwm_cap = m->pwm_cap;
    out->setpoint_u = 0;
    out->setpoint_ddps = 0;
    out->reset_loop = false;
    out->holding = false;
    if (m->stream_us < KM_STREAM_GAP_US + 1u) {
        m->stream_us += dt_us;
    }
    switch (m->ts) {
    case KM_TORQUE_ON: {
        const bool done = km_profile_step(&m->profile, dt_us);
        out->bridge = KM_BRIDGE_PWM;
        out->setpoint_u = m->profile.pos;
        out->setpoint_ddps = km_profile_vel_ddps(&m->profile);
        out->reset_loop = m->reset_loop;
        out->holding = done;
        m->reset_loop = false;
        if (m->running) {
            prv_count_rotation(m, dt_us);
            if (done) {
                prv_settle_clock(m, p, position, dt_us);
                const int32_t dev = km_pos_diff(position, m->target);
                const int32_t band = (int32_t)p->gains.arrive_ddeg - KM_ARRIVE_MARGIN_DDEG;
                const bool slow = speed_ddps <= KM_ARRIVE_SPEED_DDPS && speed_ddps >= -KM_ARRIVE_SPEED_DDPS;
                if ((dev <= band && dev >= -band && slow) ||
                    m->settle_us >= (uint32_t)p->gains.settle_ms * 1000u) {
                    m->running = false; /* the motion ended: 0x4D stops counting */
                }
            }
        }
        return;
    }
    case KM_TORQUE_BRAKE:
        out->bridge = KM_BRIDGE_BRAKE;
        return;
    case KM_TORQUE_ARMED:
        /* off now: the idle output, or the power-on output before any command */
        out->bridge = (m->touched ? p->idle_brake : p->power_on_brake) ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE;
        return;
    default: /* KM_TORQUE_FREE, KM_TORQUE_PROTECTED */
        out->bridge = KM_BRIDGE_FREE;
        return;
    }
}
