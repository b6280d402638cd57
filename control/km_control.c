/* SPDX-License-Identifier: Apache-2.0 */
/* The control tick (km_control.h; docs/control-design.md "The tick"). */
#include "km_control.h"

#include <string.h>

#include "km_fixdiv.h"

/* Motor mode owns the bridge: never in a build without it
 * (KM_FEATURE_MOTOR_MODE=0, docs/footprint.md "What gives way"). */
static bool prv_motor_active(const km_control_t *c)
{
    return KM_FEATURE_MOTOR_MODE && c->motor.active;
}

void km_control_init(km_control_t *c, const km_control_params_t *p)
{
    memset(c, 0, sizeof *c);
    km_servo_mode_init(&c->servo, p);
    km_motor_mode_init(&c->motor);
    km_position_loop_init(&c->loop);
    km_speed_window_init(&c->speed);
    km_current_limit_init(&c->ilim);
    km_protect_init(&c->prot);
    km_selftest_init(&c->selftest);
    c->action = KM_PROT_ACT_NONE;
    c->frame = km_axis_of(p);
    /* §5.1 0x11 bit 0: the power-on output until the first tick says otherwise */
    c->bridge = km_output_bridge(p->power_on_brake ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE, 0, 0, false);
}

/* A position of the old frame in the new one: km_axis_map's value, which
 * is sign x pos + where the old frame's 0 is in the new one, modulo 2^32. */
static int32_t prv_map(int32_t sign, uint32_t zero, int32_t pos)
{
    return km_s32((uint32_t)sign * (uint32_t)pos + zero);
}

/* The speed estimates and the hold filter into the new frame. */
static void prv_rebase_axis_speeds(km_control_t *c, int32_t sign, uint32_t zero)
{
    for (uint32_t k = 0; k < KM_SPEED_FAST_N; k++) {
        c->fast.pos[k] = prv_map(sign, zero, c->fast.pos[k]);
    }
    c->fast.ddps *= sign;
    if (KM_FEATURE_STREAM_OBS) {
        km_speed_obs_reset(&c->obs, prv_map(sign, zero, c->obs.base), c->fast.ddps);
    }
    c->speed.last_position = prv_map(sign, zero, c->speed.last_position);
    c->speed.acc *= sign;
    c->speed.dps *= sign;
    c->hold.out = prv_map(sign, zero, c->hold.out);
    c->hold.frac *= sign;
}

/* 0. the master's frame changed: control's state follows it, the shaft
 * stays where it is. */
static void prv_rebase_axis(km_control_t *c, const km_axis_t *now)
{
    const km_axis_t was = c->frame;
    const int32_t sign = km_axis_sign(&was, now);
    const uint32_t zero = (uint32_t)km_axis_map(&was, now, 0);
    c->frame = *now;
    if (!c->have_position) {
        return;
    }
    prv_rebase_axis_speeds(c, sign, zero);
    c->position = prv_map(sign, zero, c->position);
    if (prv_motor_active(c)) {
        km_motor_mode_reaxis(&c->motor, &was, now);
    } else if (c->servo.ts == KM_TORQUE_ON) {
        const bool moving = c->servo.running;
        const int32_t held = moving ? km_profile_pos_ddeg(&c->servo.profile) : c->servo.target;
        km_servo_mode_rebase(&c->servo, prv_map(sign, zero, held));
        c->servo.running = moving;
        c->servo.reset_loop = false;
        c->loop.i_acc *= sign;
        c->loop.last_sp_ddps = 0;
        c->loop.last_sp_sub = 0;
    }
}

/* Follows the master's frame of `p` (km_axis.h) when it changed. */
static void prv_follow_axis(km_control_t *c, const km_control_params_t *p)
{
    if (km_axis_differs(&c->frame, p)) {
        const km_axis_t now = km_axis_of(p);
        prv_rebase_axis(c, &now);
    }
}

/* A torque switch for servo mode: motor mode lets go of the bridge. */
static bool prv_torque(km_control_t *c, km_torque_t torque)
{
    if (prv_motor_active(c)) {
        km_motor_mode_release(&c->motor);
    }
    return km_servo_mode_torque(&c->servo, torque, c->position);
}

/* A motor run: ends a servo-mode hold or move (refused in a build without
 * motor mode, whose dispatcher sends none). */
static bool prv_request_motor(km_control_t *c, const km_request_t *req, const km_control_params_t *p)
{
    if (!KM_FEATURE_MOTOR_MODE) {
        return false;
    }
    km_motor_mode_run(&c->motor, &req->u.run, p, c->position);
    c->servo.running = false;
    c->servo.streaming = false;
    return true;
}

/* While protecting: only a request for less motion (`less`) is taken;
 * FREE/BRAKE is what 0x64 returns to, a motor stop stays after the release. */
static bool prv_request_protecting(km_control_t *c, const km_request_t *req, const km_control_params_t *p,
                                   bool less)
{
    if (!less) {
        return false;
    }
    if (req->kind != KM_REQ_TORQUE) {
        return prv_request_motor(c, req, p);
    }
    c->ts_after = req->u.torque;
    return prv_torque(c, (km_torque_t)req->u.torque);
}

/* A torque switch or a move: servo mode takes the shaft back from the motor. */
static bool prv_request_servo(km_control_t *c, const km_request_t *req, const km_control_params_t *p)
{
    if (prv_motor_active(c) && c->servo.ts == KM_TORQUE_ON) {
        km_servo_mode_rebase(&c->servo, c->position);
    }
    const bool ok = req->kind == KM_REQ_TORQUE
                        ? km_servo_mode_torque(&c->servo, (km_torque_t)req->u.torque, c->position)
                        : km_servo_mode_move(&c->servo, &req->u.move, p, c->position);
    if (ok && KM_FEATURE_MOTOR_MODE) {
        km_motor_mode_release(&c->motor);
    }
    return ok;
}

/* A clear request (0x36); what it released goes into the next tick's events. */
static bool prv_clear(km_control_t *c, uint8_t mask)
{
    const uint8_t was = km_protect_active(&c->prot);
    if (!km_protect_clear(&c->prot, mask)) {
        return false;
    }
    c->cleared |= (uint8_t)(was & (uint8_t)~km_protect_active(&c->prot));
    return true;
}

KM_COMPACT_NOINLINE bool km_control_request(km_control_t *c, const km_request_t *req,
                                            const km_control_params_t *p)
{
    prv_follow_axis(c, p);
    c->requests++;
    c->last_request = *req;
    if (req->kind == KM_REQ_PROTECTION_CLEAR) {
        return prv_clear(c, req->u.clear);
    }
    if (req->kind == KM_REQ_ZERO_POSITION) {
        return true; /* the dispatcher moves the offsets; nothing moves here */
    }
    const bool less = km_request_less_motion(req);
    if (c->hw != 0u && !less) {
        return false; /* §5.2 0x35: a hardware fault blocks motion until restart; a stop is taken */
    }
    if (c->action != KM_PROT_ACT_NONE) {
        return prv_request_protecting(c, req, p, less);
    }
    switch (req->kind) {
    case KM_REQ_TORQUE:
    case KM_REQ_MOVE:
        return prv_request_servo(c, req, p);
    case KM_REQ_MOTOR:
        return prv_request_motor(c, req, p);
    default:
        return false; /* not a control request */
    }
}

/* A protection began acting (`was` none) or changed its action. */
static void prv_protect_act(km_control_t *c, km_prot_action_t act, km_prot_action_t was)
{
    if (was == KM_PROT_ACT_NONE) {
        c->ts_after = c->servo.ts <= KM_TORQUE_BRAKE ? c->servo.ts : (uint8_t)KM_TORQUE_ARMED;
    }
    if (prv_motor_active(c)) {
        km_motor_mode_stop(&c->motor, act == KM_PROT_ACT_FREE ? KM_BRIDGE_FREE : KM_BRIDGE_BRAKE);
    }
    if (act == KM_PROT_ACT_HOLD && c->servo.ts == KM_TORQUE_ON && !prv_motor_active(c)) {
        if (was == KM_PROT_ACT_NONE) {
            /* a move stops where the shaft is; a hold keeps its loop's integral */
            if (c->servo.running || c->servo.streaming) {
                km_servo_mode_rebase(&c->servo, c->position);
            }
            c->ts_after = KM_TORQUE_ON;
        }
    } else if (c->servo.ts > KM_TORQUE_BRAKE) {
        km_servo_mode_protect(&c->servo); /* motion stops; 0x64 = 5 */
        if (c->ts_after == KM_TORQUE_ON) {
            c->ts_after = KM_TORQUE_ARMED; /* the output was let go: armed, not holding */
        }
    }
}

/* A protection's action began, changed or ended (km_control.h for 0x64). */
static KM_COMPACT_NOINLINE void prv_protect_transition(km_control_t *c, km_prot_action_t act)
{
    const km_prot_action_t was = (km_prot_action_t)c->action;
    if (act == was) {
        return;
    }
    c->action = (uint8_t)act;
    if (act != KM_PROT_ACT_NONE) {
        prv_protect_act(c, act, was);
    } else if (c->ts_after != KM_TORQUE_ON) {
        (void)km_servo_mode_torque(&c->servo, (km_torque_t)c->ts_after, c->position);
    }
}

/* §5.2 0x35: a hardware fault stops everything, the output free. */
static void prv_hw_fault(km_control_t *c)
{
    if (prv_motor_active(c)) {
        km_motor_mode_stop(&c->motor, KM_BRIDGE_FREE);
    }
    if (c->servo.ts != KM_TORQUE_PROTECTED) {
        (void)km_servo_mode_torque(&c->servo, KM_TORQUE_FREE, c->position);
    }
    c->ts_after = KM_TORQUE_FREE;
}

/* §5.1: position = sensor + 0x16 + 0x17, negated by 0x11 bit 2. */
static int32_t prv_position(const km_control_t *c, const km_sensors_t *in)
{
    return km_axis_position(&c->frame, in->position);
}

/* The position control works on: through the hold filter while holding still. */
static int32_t prv_hold_position(km_control_t *c, int32_t pos)
{
    const bool hold =
        !c->servo.running && c->servo.profile.done && c->servo.ts == KM_TORQUE_ON && !prv_motor_active(c);
    if (!hold && !c->hold.on) {
        return pos; /* moving: the reading as is */
    }
    km_hold_filter_set(&c->hold, hold, pos);
    return km_hold_filter_step(&c->hold, pos);
}

/* The sub-count observer on the raw reading, while a 0x68 stream runs
 * (started where the shaft is when the stream starts). */
static void prv_observe(km_control_t *c, int32_t raw, uint32_t dt_us)
{
    if (!KM_FEATURE_STREAM_OBS || !c->servo.streaming) {
        c->obs_on = false;
        return;
    }
    if (!c->obs_on) {
        km_speed_obs_reset(&c->obs, raw, c->fast.ddps);
        c->obs_on = true;
    }
    c->obs_ddps = km_speed_obs_step(&c->obs, raw, dt_us);
}

/* 1. sensing: the position `pos` (master's frame), its speeds, the clock.
 * Returns the fast speed (0.1 deg/s) the loops damp with; *speed_dps the
 * 20 ms window's (0x47). */
static KM_COMPACT_NOINLINE int32_t prv_sense(km_control_t *c, int32_t raw, int32_t pos, uint32_t dt_us,
                                             int32_t *speed_dps)
{
    if (!c->have_position) {
        km_speed_fast_init(&c->fast, pos);
    }
    prv_observe(c, raw, dt_us);
    *speed_dps = km_speed_window_step(&c->speed, pos, dt_us);
    const int32_t speed_ddps = c->have_position ? km_speed_fast_step(&c->fast, pos, dt_us) : 0;
    c->position = pos;
    c->have_position = true;
    c->time_rem_us += dt_us;
    while (c->time_rem_us >= 1000u) { /* once per 1 ms tick: no divide */
        c->time_rem_us -= 1000u;
        c->time_ms++;
    }
    return speed_ddps;
}

/* 2. self-test and protection; returns the hardware faults found at this tick. */
static KM_COMPACT_NOINLINE uint8_t prv_supervise(km_control_t *c, const km_sensors_t *in,
                                                 const km_control_params_t *p, int32_t pos, uint32_t dt_us,
                                                 km_live_t *live)
{
    const int32_t drive = c->bridge.mode == KM_BRIDGE_PWM ? c->bridge.pwm : 0;
    const uint8_t hw = km_selftest_step(&c->selftest, in, p, drive, c->bridge.mode == KM_BRIDGE_FREE, dt_us);
    const uint8_t hw_found = (uint8_t)(hw & (uint8_t)~c->hw);
    if (hw != c->hw) {
        c->hw = hw;
        prv_hw_fault(c);
    }
    const km_protect_in_t pin = {
        .voltage_mv = in->voltage_mv,
        .current_ma = in->current_ma,
        .temperature_c10 = in->temperature_c10,
        .position = pos,
        .drive_pwm = drive,
        .servo_mode = !prv_motor_active(c),
    };
    prv_protect_transition(c, km_protect_step(&c->prot, &pin, p, dt_us, &live->events));
    return hw_found;
}

/* The output bound of this tick: min(0x5B, 0x13, the 0x5C/0x14 cap). */
static int32_t prv_limit(km_control_t *c, const km_sensors_t *in, const km_control_params_t *p)
{
    const int32_t limit = p->torque_limit < p->max_torque ? p->torque_limit : p->max_torque;
    const uint32_t ilimit = p->current_limit_ma < p->max_current_ma ? p->current_limit_ma : p->max_current_ma;
    const int32_t icap = km_current_limit_step(&c->ilim, in->current_ma, ilimit);
    return icap < limit ? icap : limit;
}

/* 3. motor mode owns the bridge; 0x5A = 1 (servo only) stops it. */
static KM_COMPACT_NOINLINE void prv_drive_motor(km_control_t *c, const km_control_params_t *p, int32_t pos,
                                                int32_t speed_ddps, uint32_t dt_us, int32_t limit)
{
    if (p->control_mode == KM_MODE_SERVO_ONLY && c->motor.running) {
        km_motor_mode_stop(&c->motor, p->idle_brake ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE);
    }
    km_bridge_mode_t mode;
    const int32_t mpwm = km_motor_mode_step(&c->motor, p, pos, speed_ddps, dt_us, &mode);
    c->bridge = km_output_bridge(mode, mpwm, limit, p->reverse);
}

/* 4. the 0x5D governor: the drive cut while the shaft exceeds 0.9 x 0x5D. */
static int32_t prv_speed_governor(const km_control_params_t *p, int32_t pwm, int32_t speed_ddps)
{
    const int32_t dps = (int32_t)p->speed_limit_dps;
    if (dps == 0 || dps >= (int32_t)p->gains.fastest_dps) {
        return pwm;
    }
    const int32_t excess = (pwm >= 0 ? speed_ddps : -speed_ddps) - dps * 9;
    if (excess <= 0) {
        return pwm;
    }
    const int32_t cap = km_sdiv2560((int32_t)p->gains.kv_q8 * dps * 9) + (int32_t)p->gains.friction_pwm -
                        km_sdiv2560((int32_t)p->gains.kd_q8 * (excess > 20000 ? 20000 : excess));
    if (pwm >= 0) {
        return pwm > cap ? cap : pwm;
    }
    return -pwm > cap ? -cap : pwm;
}

/* 3. servo mode and the position loop, 4. output. */
static KM_COMPACT_NOINLINE void prv_drive_servo(km_control_t *c, const km_control_params_t *p, int32_t pos,
                                                int32_t speed_ddps, uint32_t dt_us, int32_t limit)
{
    km_servo_mode_out_t sm;
    km_servo_mode_step(&c->servo, p, pos, speed_ddps, dt_us, &sm);
    if (sm.pwm_cap < limit) {
        limit = sm.pwm_cap;
    }
    int32_t pwm = 0;
    if (sm.bridge == KM_BRIDGE_PWM) {
        if (sm.reset_loop) {
            km_position_loop_init(&c->loop);
        }
        const bool stream = c->servo.streaming && !c->servo.profile.done;
        const bool obs = KM_FEATURE_STREAM_OBS && stream;
        const km_position_loop_in_t li = {
            .setpoint_u = obs ? sm.setpoint_u - km_speed_obs_frac_u(&c->obs) : sm.setpoint_u,
            .setpoint_ddps = sm.setpoint_ddps,
            .setpoint_sub = stream ? c->servo.profile.vel - sm.setpoint_ddps * 1000 : 0,
            .position = km_pos_diff(obs ? c->obs.base : pos,
                                    c->servo.profile.origin), /* from the set-point's origin */
            .speed_ddps = obs ? c->obs_ddps : speed_ddps,
            .pwm_max = limit,
            /* not under a protection's hold or a closing current limit */
            .integrate = sm.holding && c->action == KM_PROT_ACT_NONE && c->ilim.cap >= KM_CURRENT_LIMIT_OPEN,
            .unwind = sm.holding && c->ilim.cap >= KM_CURRENT_LIMIT_OPEN,
            .still = c->hold.on && c->action == KM_PROT_ACT_NONE,
            .stream = stream,
        };
        pwm = prv_speed_governor(p, km_position_loop_step(&c->loop, &p->gains, &li, dt_us), speed_ddps);
    }
    c->bridge = km_output_bridge(sm.bridge, pwm, limit, p->reverse);
}

/* 4b. the protection's action has the last word on the bridge. */
static void prv_protect_output(km_control_t *c)
{
    if (c->action == KM_PROT_ACT_FREE || c->action == KM_PROT_ACT_BRAKE ||
        (c->action == KM_PROT_ACT_HOLD && c->servo.ts != KM_TORQUE_ON)) {
        c->bridge.mode = c->action == KM_PROT_ACT_BRAKE ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE;
        c->bridge.pwm = 0;
    }
}

/* What this tick reports: every field of live but the supervisor's events. */
static void prv_report(km_control_t *c, const km_sensors_t *in, int32_t pos, int32_t speed_dps,
                       bool was_acting, uint8_t hw_found, km_live_t *live)
{
    const bool motor = prv_motor_active(c);
    live->position = pos;
    live->speed = speed_dps;
    live->current = in->current_ma;
    live->pwm = km_output_pwm_reported(&c->bridge);
    if (in->temperature_c10 != c->temp_c10) { /* 0 and 0 after init: consistent */
        c->temp_c10 = in->temperature_c10;
        c->temp_c = km_sdiv10(c->temp_c10);
    }
    live->temperature = c->temp_c;
    live->voltage = in->voltage_mv;
    live->deviation = motor ? 0 : km_servo_mode_deviation(&c->servo, pos);
    live->rotation_ms = motor ? c->motor.rotation_ms : c->servo.rotation_ms;
    live->running = motor ? c->motor.running : c->servo.running;
    live->protecting = c->action != KM_PROT_ACT_NONE;
    live->torque_forced = live->protecting || was_acting || hw_found != 0u;
    live->torque_switch = live->protecting ? (uint8_t)KM_TORQUE_PROTECTED : c->servo.ts;
    live->protections = km_protect_active(&c->prot);
    live->hw_faults = c->hw;
    live->events.cleared = c->cleared;
    live->events.hw_found = hw_found;
    c->cleared = 0u;
    live->time_ms = c->time_ms;
}

void km_control_step(km_control_t *c, const km_sensors_t *in, const km_control_params_t *p, uint32_t dt_us,
                     km_live_t *live, km_bridge_t *bridge)
{
    prv_follow_axis(c, p);
    const int32_t raw = prv_position(c, in);
    const int32_t pos = prv_hold_position(c, raw);
    int32_t speed_dps;
    const int32_t speed_ddps = prv_sense(c, raw, pos, dt_us, &speed_dps);
    const bool was_acting = c->action != KM_PROT_ACT_NONE;
    const uint8_t hw_found = prv_supervise(c, in, p, pos, dt_us, live);
    const int32_t limit = prv_limit(c, in, p);
    if (prv_motor_active(c)) {
        prv_drive_motor(c, p, pos, speed_ddps, dt_us, limit);
    } else {
        prv_drive_servo(c, p, pos, speed_ddps, dt_us, limit);
    }
    prv_protect_output(c);
    prv_report(c, in, pos, speed_dps, was_acting, hw_found, live);
    bridge->mode = c->bridge.mode; /* by field: a struct copy is a memcpy call here */
    bridge->pwm = c->bridge.pwm;
}
