/* SPDX-License-Identifier: Apache-2.0 */
/* Position loop (km_position_loop.h): PID with feedforward and anti-windup. */
#include "km_position_loop.h"

#include "km_fixdiv.h"

void km_position_loop_init(km_position_loop_t *l)
{
    l->i_acc = 0;
    l->i_pwm_of = 0;
    l->i_pwm = 0;
    l->still_ms = 0;
    l->rest_pos = 0;
    l->last_sp_ddps = 0;
    l->last_sp_sub = 0;
}

/* The integrator's PWM, i_acc / 256000, divided only when i_acc changed. */
static int32_t prv_i_pwm(km_position_loop_t *l)
{
    if (l->i_acc != l->i_pwm_of) {
        l->i_pwm_of = l->i_acc;
        l->i_pwm = km_sdiv256000(l->i_acc);
    }
    return l->i_pwm;
}

/* Whether a settled hold was pushed away from where it rested (ki_hold's case). */
static bool prv_pushed(const km_position_loop_t *l, const km_control_gains_t *g,
                       const km_position_loop_in_t *in)
{
    const int32_t pushed = in->position - l->rest_pos; /* from where the settled hold rested */
    return l->still_ms >= KM_HOLD_SETTLED_MS && g->ki_hold_q4 != 0u &&
           (pushed > KM_HOLD_PUSH_DDEG || pushed < -KM_HOLD_PUSH_DDEG);
}

/* The integrator gain while holding still, or -1 when it waits this tick. */
static int32_t prv_hold_ki(km_position_loop_t *l, const km_control_gains_t *g,
                           const km_position_loop_in_t *in, int32_t e_u, int32_t e_d, bool in_band)
{
    if (in_band) {
        const int32_t small = 2 * (int32_t)g->friction_pwm, i_pwm = prv_i_pwm(l);
        if (i_pwm <= small && i_pwm >= -small) {
            l->i_acc -= l->i_acc / 128;
        }
        return -1;
    }
    const bool push = prv_pushed(l, g, in);
    if ((e_u > 0 && in->speed_ddps > KM_HOLD_RETURN_DDPS) ||
        (e_u < 0 && in->speed_ddps < -KM_HOLD_RETURN_DDPS)) {
        if (push && e_d <= KM_HOLD_BLEED_DDEG && e_d >= -KM_HOLD_BLEED_DDEG) {
            l->i_acc -= l->i_acc / 512 * KM_HOLD_RETURN_BLEED_Q9;
        }
        return -1;
    }
    if (!push) {
        return (int32_t)g->ki_q8;
    }
    const int32_t ki = (int32_t)g->ki_hold_q4 * 16; /* Q4 -> Q8 */
    return ki + ((ki * (e_d < 0 ? -e_d : e_d) * KM_HOLD_KI_GROW_Q6) >> 6);
}

/* ki x e / 10 (ki_e) x dt / 100, dt capped at 2 ms, without overflowing:
 * the quotient split at 100 gives C's result exactly (docs/tuning.md). */
KM_COMPACT_NOINLINE static int32_t prv_integral_step(int32_t ki_e, uint32_t dt_us)
{
    if (dt_us == 1000u) {
        return ki_e * 10; /* hundreds x 1000 + the rest x 10: no divide at the 1 ms tick */
    }
    const int32_t dt = (int32_t)(dt_us > 2000u ? 2000u : dt_us);
    const int32_t hundreds = km_sdiv100(ki_e);
    return hundreds * dt + km_sdiv100((ki_e - hundreds * 100) * dt);
}

/* The integrator's PWM after this tick: ki x the error (u), frozen while
 * the output is saturated the way it would push (docs/tuning.md). */
static int32_t prv_integrate(km_position_loop_t *l, const km_control_gains_t *g,
                             const km_position_loop_in_t *in, int32_t e_u, bool in_band, int32_t before,
                             uint32_t dt_us)
{
    int32_t i_pwm = prv_i_pwm(l);
    /* 10 deg: the integrator is for small errors */
    const int32_t e_d = km_sat(km_sdiv1000(e_u), 100);
    int32_t ki = (int32_t)g->ki_q8;
    if (KM_FEATURE_HOLD_KI && in->still) {
        ki = prv_hold_ki(l, g, in, e_u, e_d, in_band);
        if (ki < 0) {
            return prv_i_pwm(l);
        }
    }
    const int32_t i_max = (g->i_max_pwm > 1000u ? 1000 : (int32_t)g->i_max_pwm) * 256000;
    const int32_t di = prv_integral_step(km_sdiv10(ki * e_d), dt_us);
    before += i_pwm;
    if (!((before >= in->pwm_max && di > 0) || (before <= -in->pwm_max && di < 0))) {
        l->i_acc = km_sat(l->i_acc + di, i_max);
        i_pwm = prv_i_pwm(l);
    }
    return i_pwm;
}

/* Whether the shaft stands past the target, beyond KM_HOLD_PAST_DDEG, the
 * way the integrator pushes: it holds more than any load (docs/tuning.md
 * "A load let go"). */
static bool prv_pushed_past(const km_position_loop_t *l, int32_t e_u)
{
    const int32_t past_u = KM_HOLD_PAST_DDEG * 1000;
    return (l->i_acc > 0 && e_u < -past_u) || (l->i_acc < 0 && e_u > past_u);
}

/* Holding still: the hold band as a dead band and the settled clock;
 * returns kp (kp_hold once settled). */
static int32_t prv_hold_terms(km_position_loop_t *l, const km_control_gains_t *g,
                              const km_position_loop_in_t *in, int32_t *e_u, int32_t *ev, uint32_t dt_us,
                              bool *in_band)
{
    const int32_t band_u = (int32_t)g->hold_band_ddeg * 1000;
    *in_band = *e_u <= band_u && *e_u >= -band_u;
    if (*in_band) {
        *e_u = 0;
        *ev = 0;
    } else {
        *e_u += *e_u > 0 ? -band_u : band_u;
    }
    if (l->still_ms < KM_HOLD_SETTLED_MS) { /* settled: the position unchanged that long */
        l->still_ms = in->position == l->rest_pos ? l->still_ms + (dt_us >= 1000u ? 1 : 0) : 0;
        l->rest_pos = in->position;
    }
    const bool settled = l->still_ms >= KM_HOLD_SETTLED_MS && g->kp_hold_q8 != 0u;
    return settled ? (int32_t)g->kp_hold_q8 : (int32_t)g->kp_q8;
}

/* tau x the set-point speed's change this tick (0.1 deg/s x ms); a
 * stream's from its speed in 0.001 x 0.1 deg/s. */
static int32_t prv_accel_ff(km_position_loop_t *l, const km_position_loop_in_t *in, int32_t vs, int32_t tau)
{
    int32_t va;
    if (in->stream) {
        const int32_t sub = km_sat_inline(in->setpoint_sub, 999);
        const int32_t dvs_u = km_sat_inline((vs - l->last_sp_ddps) * 1000 + sub - l->last_sp_sub, 2000000);
        va = km_sdiv1000(dvs_u * tau);
        l->last_sp_sub = sub;
    } else {
        va = km_sat_inline(vs - l->last_sp_ddps, 20000) * tau;
        l->last_sp_sub = 0;
    }
    l->last_sp_ddps = vs;
    return va;
}

int32_t km_position_loop_step(km_position_loop_t *l, const km_control_gains_t *g,
                              const km_position_loop_in_t *in, uint32_t dt_us)
{
    /* error in u, bounded to +-200 deg */
    const int32_t pos_u = km_sat_inline(in->position, 1000000) * 1000;
    const int32_t sp_u = km_sat_inline(in->setpoint_u, 1000000000);
    int32_t e_u = km_sat_inline(sp_u - pos_u, 2000000);
    const int32_t vs = km_sat_inline(in->setpoint_ddps, 20000);
    int32_t ev = km_sat_inline(vs - km_sat_inline(in->speed_ddps, 20000), 20000);
    int32_t kp = (int32_t)g->kp_q8, kd = (int32_t)g->kd_q8;
    bool in_band = false;
    if (in->still) {
        kp = prv_hold_terms(l, g, in, &e_u, &ev, dt_us, &in_band);
    } else {
        l->still_ms = 0;
    }
    if (in->stream) {
        kp >>= KM_STREAM_KP_SHIFT;
        kd >>= KM_STREAM_KD_SHIFT;
    }
    /* kp: PWM per 0.1 deg Q8 */
    int32_t out = km_sdiv2560(kp * km_sdiv100(e_u));
    out += km_sdiv2560(kd * ev); /* kd: PWM per deg/s Q8, ev 0.1 deg/s */
    /* acceleration feedforward: tau x dv/dt as a speed, 0.1 deg/s */
    int32_t va = prv_accel_ff(l, in, vs, g->tau_ms > 1000u ? 1000 : (int32_t)g->tau_ms);
    if (dt_us >= 2000u) { /* over dt in ms, at least 1 */
        va /= (int32_t)km_udiv1000(dt_us);
    }
    va = km_sat_inline(va, 20000);
    out += km_sdiv2560((int32_t)g->kv_q8 * km_sat_inline(vs + va, 20000)); /* kv: PWM per deg/s Q8 */
    if (vs != 0) {
        out += vs > 0 ? (int32_t)g->friction_pwm : -(int32_t)g->friction_pwm;
    }
    if (in->unwind && prv_pushed_past(l, e_u)) {
        l->i_acc = l->i_acc / KM_HOLD_PAST_BLEED * (KM_HOLD_PAST_BLEED - 1); /* reaches 0 */
        out += prv_i_pwm(l);
    } else if (in->integrate) {
        out += prv_integrate(l, g, in, e_u, in_band, out, dt_us);
    } else {
        out += prv_i_pwm(l);
    }
    return km_sat_inline(out, in->pwm_max);
}
