/* The control tick (see km_control.h): sensing, servo mode, position loop
 * and output stage, in that order, once per tick. */
#include "km_control.h"

#include <string.h>

#include "km_fixdiv.h"

void km_control_init(km_control_t *c, const km_control_params_t *p)
{
    memset(c, 0, sizeof *c);
    km_servo_mode_init(&c->servo, p);
    km_motor_mode_init(&c->motor);
    km_position_loop_init(&c->loop);
    km_speed_window_init(&c->speed);
    /* §5.1 0x11 bit 0: the power-on output until the first tick says otherwise */
    c->bridge = km_output_bridge(p->power_on_brake ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE, 0, 0, false);
}

bool km_control_request(km_control_t *c, const km_request_t *req, const km_control_params_t *p)
{
    c->requests++;
    c->last_request = *req;
    switch (req->kind) {
    case KM_REQ_TORQUE_SWITCH:
    case KM_REQ_MOVE_TIME:
    case KM_REQ_MOVE_SPEED:
    case KM_REQ_SERVO_ADVANCED:
    case KM_REQ_INTERPOLATE: {
        /* a servo command (or torque switch) takes the shaft back from the
         * motor: servo mode restarts from where the shaft is */
        if (c->motor.active && c->servo.ts == 2u) {
            km_servo_mode_rebase(&c->servo, c->position);
        }
        const bool ok = km_servo_mode_request(&c->servo, req, p, c->position);
        if (ok) {
            km_motor_mode_release(&c->motor);
        }
        return ok;
    }
    case KM_REQ_MOTOR_TORQUE:
    case KM_REQ_MOTOR_SPEED:
    case KM_REQ_MOTOR_ADVANCED:
        /* the variant and 0x5A rules are the dispatcher's; a motor command
         * ends a servo-mode hold or move (km_motor_mode.h) */
        if (!km_motor_mode_request(&c->motor, req, p, c->position)) {
            return false;
        }
        c->servo.running = false;
        c->servo.streaming = false;
        return true;
    default:
        /* zeroing, protection clear: later issues; accepted as before */
        return true;
    }
}

/* §5.1: reported position = sensor + level-1 + level-2 zero offsets, with
 * the sign flipped when 0x11 bit 2 makes counter-clockwise positive. */
static int32_t prv_position(const km_sensors_t *in, const km_control_params_t *p)
{
    const int32_t pos = in->position + p->zero_offset1 + p->zero_offset2;
    return p->reverse ? -pos : pos;
}

void km_control_step(km_control_t *c, const km_sensors_t *in, const km_control_params_t *p,
                     uint32_t dt_us, km_live_t *live, km_bridge_t *bridge)
{
    /* 1. sensing */
    const int32_t pos = prv_position(in, p);
    if (!c->have_position) {
        km_speed_fast_init(&c->fast, pos);
    }
    const int32_t speed_dps = km_speed_window_step(&c->speed, pos, dt_us);
    const int32_t speed_ddps = c->have_position ? km_speed_fast_step(&c->fast, pos, dt_us) : 0;
    c->position = pos;
    c->have_position = true;

    int32_t limit = p->torque_limit < p->max_torque ? p->torque_limit : p->max_torque;
    if (c->motor.active) {
        /* 2b. motor mode owns the bridge (servo mode's output is unused);
         * 0x5A = 1 (servo only) stops it. Output limited by 0x5B. */
        if (p->control_mode == 1u && c->motor.running) {
            km_motor_mode_stop(&c->motor, p->idle_brake ? KM_BRIDGE_BRAKE : KM_BRIDGE_FREE);
        }
        km_bridge_mode_t mode;
        const int32_t mpwm = km_motor_mode_step(&c->motor, p, pos, speed_ddps, dt_us, &mode);
        c->bridge = km_output_bridge(mode, mpwm, limit, p->reverse);
    } else {
        /* 2. servo mode. Not stepped while the motor owns the bridge: its
         * output would be unused, and the hand-back (km_control_request)
         * restarts it from where the shaft is (rebase or torque on). */
        km_servo_mode_out_t sm;
        km_servo_mode_step(&c->servo, p, pos, dt_us, &sm);
        /* 3. position loop, 4. output */
        if (sm.pwm_cap < limit) {
            limit = sm.pwm_cap;
        }
        int32_t pwm = 0;
        if (sm.bridge == KM_BRIDGE_PWM) {
            if (sm.reset_loop) {
                km_position_loop_init(&c->loop);
            }
            const km_position_loop_in_t li = {
                .setpoint_u = sm.setpoint_u,
                .setpoint_ddps = sm.setpoint_ddps,
                .position = pos,
                .speed_ddps = speed_ddps,
                .pwm_max = limit,
                .integrate = sm.holding,
            };
            pwm = km_position_loop_step(&c->loop, &p->gains, &li, dt_us);
        }
        c->bridge = km_output_bridge(sm.bridge, pwm, limit, p->reverse);
    }

    /* every field assigned (no memset: it is a byte loop on the M0) */
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
    live->deviation = c->motor.active ? 0 : km_servo_mode_deviation(&c->servo, pos);
    live->rotation_ms = c->motor.active ? c->motor.rotation_ms : c->servo.rotation_ms;
    live->running = c->motor.active ? c->motor.running : c->servo.running;
    live->protecting = c->servo.ts == 5u;
    live->protections = 0u; /* the protection supervisor's: a later issue */
    live->hw_faults = in->faults;
    bridge->mode = c->bridge.mode; /* by field: a struct copy is a memcpy call here */
    bridge->pwm = c->bridge.pwm;
}
