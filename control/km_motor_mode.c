/* SPDX-License-Identifier: Apache-2.0 */
/* Motor mode: constant PWM, constant speed, counted runs (see
 * km_motor_mode.h for the rules). */
#include "km_motor_mode.h"

#include <string.h>

#include "km_fixdiv.h"

void km_motor_mode_init(km_motor_mode_t *m)
{
    memset(m, 0, sizeof *m);
    m->stop_bridge = KM_BRIDGE_FREE;
}

void km_motor_mode_release(km_motor_mode_t *m)
{
    m->active = false;
    m->running = false;
}

void km_motor_mode_stop(km_motor_mode_t *m, km_bridge_mode_t bridge)
{
    m->running = false;
    m->stop_bridge = bridge;
}

/* Speed runs and counted angles or turns are for encoder products only
 * (§6 "Encoder-only commands": the dispatcher refuses them on a
 * potentiometer product), so motor mode takes their paths only on an
 * encoder product; where the board fixes a potentiometer variant
 * (km_params_variant) they fold away. */
static bool prv_encoder(const km_control_params_t *p)
{
    return km_params_variant(p) == KM_VARIANT_ENCODER;
}

/* The run is a speed run (encoder products only). */
static bool prv_speed_run(const km_motor_mode_t *m, const km_control_params_t *p)
{
    return prv_encoder(p) && m->speed_mode;
}

/* The run counts an angle or turns (encoder products only). */
static bool prv_counts_travel(const km_motor_mode_t *m, const km_control_params_t *p)
{
    return prv_encoder(p) && m->count_kind >= KM_UNTIL_ANGLE;
}

/* Speed set-point cut to 0x5D (0x15 when 0x5D is 0). */
static int32_t prv_speed(const km_control_params_t *p, int32_t dps)
{
    int32_t lim = p->speed_limit_dps ? p->speed_limit_dps : p->max_speed_dps;
    if (lim == 0) {
        lim = p->gains.fastest_dps;
    }
    lim = lim > 20000 ? 20000 : lim; /* keeps the loop's products in 32 bits */
    return km_sat(dps, lim);
}

static void prv_start(km_motor_mode_t *m, const km_control_params_t *p, bool speed_mode, int32_t value,
                      km_bridge_mode_t stop_bridge)
{
    m->active = true;
    m->stop_bridge = stop_bridge;
    m->count_kind = 0;
    if (speed_mode != prv_speed_run(m, p) || !m->running) {
        m->i_acc = 0;
    }
    m->speed_mode = speed_mode;
    m->pwm = speed_mode ? 0 : value;
    m->speed_dps = speed_mode ? value : 0;
    m->running = value != 0;
    m->rotation_ms = 0;
    m->rotation_rem_us = 0;
}

/* The output once a run stops. */
static km_bridge_mode_t prv_after(const km_motor_run_t *run, const km_control_params_t *p)
{
    if (run->after == KM_AFTER_IDLE) {
        return p->idle_brake ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE;
    }
    return run->after == KM_AFTER_BRAKE ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE;
}

void km_motor_mode_run(km_motor_mode_t *m, const km_motor_run_t *run, const km_control_params_t *p,
                       int32_t position)
{
    const km_bridge_mode_t after = prv_after(run, p);
    if (run->mode == KM_RUN_STOP) {
        m->active = true;
        km_motor_mode_stop(m, after);
        return;
    }
    const bool speed_mode = prv_encoder(p) && run->mode == KM_RUN_SPEED;
    const int32_t mag = (int32_t)run->value, dir_mag = run->reverse ? -mag : mag;
    const int32_t v = speed_mode ? prv_speed(p, dir_mag) : km_sat(dir_mag, 1000);
    prv_start(m, p, speed_mode, v, after);
    const uint32_t amount = run->amount;
    m->count_kind = run->until;
    m->start_pos = position;
    m->remain_ms = run->until == KM_UNTIL_TIME ? amount * 100u : 0u; /* 0.1 s units */
    m->travel =
        run->until == KM_UNTIL_ANGLE ? (int32_t)amount * 10 : (int32_t)amount * 360; /* 1 deg, 0.1 turn */
    if (run->until != KM_UNTIL_NONE && amount == 0u) {
        m->running = false; /* a run of nothing ends at once */
    }
}

/* How far a counted run has turned from its start (modular distance:
 * defined across the int32 wrap of a long run). */
static int32_t prv_moved(const km_motor_mode_t *m, int32_t position)
{
    uint32_t moved = (uint32_t)position - (uint32_t)m->start_pos;
    moved = moved > 0x80000000u ? 0u - moved : moved;
    return moved > 0x7FFFFFFFu ? INT32_MAX : (int32_t)moved;
}

/* 0x4D and the counted run: time off, or travel done; stops the motor
 * when it ends. */
static void prv_count(km_motor_mode_t *m, const km_control_params_t *p, int32_t position, uint32_t dt_us)
{
    m->rotation_rem_us += dt_us;
    const uint32_t ms = km_udiv1000(m->rotation_rem_us);
    m->rotation_rem_us -= ms * 1000u;
    m->rotation_ms += ms;
    if (m->count_kind == KM_UNTIL_TIME) {
        m->remain_ms = m->remain_ms > ms ? m->remain_ms - ms : 0u;
        if (m->remain_ms == 0u) {
            km_motor_mode_stop(m, m->stop_bridge);
        }
    } else if (prv_counts_travel(m, p)) {
        if (prv_moved(m, position) >= m->travel) {
            km_motor_mode_stop(m, m->stop_bridge);
        }
    }
}

/* The speed loop (0.1 deg/s): feedforward kv x speed and friction, kd x
 * the speed error and a bounded integrator; the PWM in +-1000. */
static int32_t prv_speed_loop(km_motor_mode_t *m, const km_control_gains_t *g, int32_t sp_ddps,
                              int32_t speed_ddps, uint32_t dt_us)
{
    const int32_t sp = km_sat(sp_ddps, 200000);
    const int32_t err = km_sat(sp - km_sat(speed_ddps, 1000000), 20000);
    const uint32_t dt = dt_us > 2000u ? 2000u : dt_us;
    m->i_acc += km_sdiv10(km_sdiv1000(KM_MOTOR_KI_Q8 * err) * (int32_t)dt); /* PWM x 256000 */
    const int32_t imax = (int32_t)(g->i_max_pwm > 1000u ? 1000u : g->i_max_pwm) * 256000;
    m->i_acc = km_sat(m->i_acc, imax);
    const int32_t kv = g->kv_q8 > 10000u ? 10000 : (int32_t)g->kv_q8; /* kv x 200000 stays in int32 */
    int32_t pwm = km_sdiv2560(kv * sp);
    pwm += sp > 0 ? (int32_t)g->friction_pwm : (sp < 0 ? -(int32_t)g->friction_pwm : 0);
    pwm += km_sdiv2560((int32_t)g->kd_q8 * err);
    pwm += km_sdiv256000(m->i_acc);
    return km_sat(pwm, 1000);
}

/* The room (0.1 deg) the run has left in its direction `dir`: to the end
 * of a counted run and, on a potentiometer product, to the edge of the
 * travel (km_axis_travel); KM_MOTOR_ROOM_FREE when nothing ends it. */
static int32_t prv_room(const km_motor_mode_t *m, const km_control_params_t *p, int32_t position, int32_t dir)
{
    int32_t room = KM_MOTOR_ROOM_FREE;
    if (prv_counts_travel(m, p)) {
        room = m->travel - prv_moved(m, position);
    }
    if (km_params_variant(p) == KM_VARIANT_POTENTIOMETER) {
        int32_t lo, hi;
        km_axis_travel(p, &lo, &hi);
        const int32_t edge = dir > 0 ? hi - position : position - lo;
        room = edge < room ? edge : room;
    }
    return room;
}

/* The square of the fastest speed ((0.1 deg/s)^2) from which the run
 * still stops within `room` (0.1 deg) at half the product acceleration:
 * v^2 = 2 (a/2) d = a d (deg/s^2, deg) x 10 in these units. */
static uint32_t prv_approach_sq(const km_control_gains_t *g, int32_t room)
{
    const uint32_t a = g->accel_dps2 > 20000u ? 20000u : (g->accel_dps2 ? g->accel_dps2 : 1u);
    const uint32_t d = room > 20000 ? 20000u : (room < 0 ? 0u : (uint32_t)room);
    return a * d * 10u;
}

/* `sq` = v^2 as a speed (0.1 deg/s), at least KM_MOTOR_CREEP_DDPS. */
static int32_t prv_approach_ddps(uint32_t sq)
{
    const int32_t v = (int32_t)km_isqrt(0u, sq);
    return v < KM_MOTOR_CREEP_DDPS ? KM_MOTOR_CREEP_DDPS : v;
}

/* |v| bounded to 20000 (0.1 deg/s): its square fits 32 bits. */
static uint32_t prv_sq(int32_t v)
{
    const uint32_t m = v < 0 ? (uint32_t)(-v) : (uint32_t)v;
    const uint32_t b = m > 20000u ? 20000u : m;
    return b * b;
}

/* A PWM run still far from its end: the constant PWM (no speed set-point
 * is this low: they are within +-200000). */
#define PRV_FAR INT32_MIN

/* The speed loop's set-point with `room` (0.1 deg) left to the end in the
 * direction `dir` of `want`: `want`, or the approach speed once the end is near,
 * and PRV_FAR for a PWM run still far from it. */
static int32_t prv_near_setpoint(bool speed_run, const km_control_gains_t *g, int32_t room, int32_t want,
                                 int32_t dir, int32_t speed_ddps)
{
    /* the loop's lag: what the shaft covers before a slower set-point bites */
    const int32_t fast = speed_ddps * dir;
    const int32_t lag = fast > 0 ? km_sdiv1000((fast > 20000 ? 20000 : fast) * KM_MOTOR_LAG_MS) : 0;
    const uint32_t sq = prv_approach_sq(g, room - lag);
    if (!speed_run && (fast < 0 || sq > prv_sq(fast + KM_MOTOR_CREEP_DDPS))) {
        return PRV_FAR;
    }
    return speed_run && sq >= prv_sq(want) ? want : dir * prv_approach_ddps(sq);
}

/* A run with an end ahead (a count or the travel's edge): ends at it, and
 * slows down before it instead of driving through (the speed set-point,
 * or a constant PWM, cut by the approach speed; the square root is taken
 * only once the end is near). */
static int32_t prv_drive(km_motor_mode_t *m, const km_control_params_t *p, int32_t position,
                         int32_t speed_ddps, uint32_t dt_us)
{
    const bool speed_run = prv_speed_run(m, p);
    const int32_t want = speed_run ? m->speed_dps * 10 : m->pwm;
    const int32_t dir = want > 0 ? 1 : -1;
    const int32_t room = prv_room(m, p, position, dir);
    if (room <= 0) {
        km_motor_mode_stop(m, m->stop_bridge); /* at the edge of the travel */
        return 0;
    }
    int32_t sp = want; /* the speed loop's set-point */
    if (room != KM_MOTOR_ROOM_FREE) {
        sp = prv_near_setpoint(speed_run, &p->gains, room, want, dir, speed_ddps);
        if (sp == PRV_FAR) {
            return m->pwm; /* far from the end: the constant PWM */
        }
    } else if (!speed_run) {
        return m->pwm;
    }
    const int32_t out = prv_speed_loop(m, &p->gains, sp, speed_ddps, dt_us);
    if (speed_run) {
        return out;
    }
    return dir > 0 ? (out < m->pwm ? out : m->pwm) : (out > m->pwm ? out : m->pwm);
}

void km_motor_mode_reaxis(km_motor_mode_t *m, const km_axis_t *was, const km_axis_t *now)
{
    const int32_t sign = km_axis_sign(was, now);
    m->start_pos = km_axis_map(was, now, m->start_pos);
    m->pwm *= sign;
    m->speed_dps *= sign;
    m->i_acc *= sign;
}

int32_t km_motor_mode_step(km_motor_mode_t *m, const km_control_params_t *p, int32_t position,
                           int32_t speed_ddps, uint32_t dt_us, km_bridge_mode_t *mode)
{
    if (!m->running) {
        *mode = m->stop_bridge;
        return 0;
    }
    prv_count(m, p, position, dt_us);
    const int32_t pwm = m->running ? prv_drive(m, p, position, speed_ddps, dt_us) : 0;
    *mode = m->running ? KM_BRIDGE_PWM : m->stop_bridge;
    return pwm;
}
