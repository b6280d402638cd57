/* SPDX-License-Identifier: Apache-2.0 */
/* The realistic servo plant: the ideal model plus two masses joined by the
 * gear train, gear and output friction, a shared supply, bridge timing, hot
 * copper and the board's sensor chain (docs/plant.md "What the realistic model
 * adds", "Notes on the code"). */
#include "km_plant_real.h"

#include <stddef.h>

#define DDEG_PER_TURN 3600
#define DDEG_PER_RAD_X1E5 57295780LL      /* (1800 / pi) * 1e5 */
#define DEFL_MAX_Q32 ((int64_t)50 << 32)  /* 5°: the deflection never exceeds it */
#define TORQUE_MAX_UNM ((int64_t)1 << 26) /* 67 N·m: keeps torque * gain in int64 */
#define SPEED_MAX_Q16 ((int32_t)(KM_PLANT_SPEED_MAX_MDPS / 100) * 65536)
#define TEMP_LIMIT_UC 2000000000
#define STIFF_MAX 200000u            /* µN·m per m° */
#define DAMP_MAX 100000u             /* µN·m per °/s */
#define ENC_PER_DDEG_Q20 1193047LL   /* 4096 / 3600 * 2^20 */
#define NOISE_UNIT_SD_X1000 147800LL /* sd of the generator's draw, x1000 */
#define EMF_MAX_MV 100000

/* exp(-(k/4)^2), k = 0..12, Q15: the Stribeck excess's shape. */
static const int16_t k_stribeck_q15[13] = {32767, 30782, 25519, 18670, 12054, 6868, 3454,
                                           1533,  600,   207,   63,    17,    4};
/* sin(2k°), k = 0..45, Q15. */
static const int16_t k_sin_q15[46] = {0,     1144,  2286,  3425,  4560,  5690,  6813,  7927,  9032,  10126,
                                      11207, 12275, 13328, 14364, 15383, 16383, 17364, 18323, 19260, 20173,
                                      21062, 21925, 22762, 23571, 24351, 25101, 25821, 26509, 27165, 27788,
                                      28377, 28932, 29451, 29934, 30381, 30791, 31163, 31498, 31794, 32051,
                                      32269, 32448, 32587, 32687, 32747, 32767};

/* a * b / 2^shift rounded to nearest, symmetric about zero. */
static int64_t prv_mulsh(int64_t a, int64_t b, unsigned shift)
{
    const int64_t m = a * b;
    const int64_t half = (int64_t)1 << (shift - 1u);
    return m < 0 ? -((-m + half) >> shift) : (m + half) >> shift;
}

/* v limited to +-lim. */
static int64_t prv_clamp64(int64_t v, int64_t lim)
{
    return v > lim ? lim : (v < -lim ? -lim : v);
}

/* |v| for int64. */
static int64_t prv_abs64(int64_t v)
{
    return v < 0 ? -v : v;
}

/* The whole 0.1° below a Q32 angle (floor, without shifting a negative). */
static int32_t prv_ddeg_floor(int64_t th_q32)
{
    return (int32_t)((int64_t)(((uint64_t)th_q32 + ((uint64_t)1 << 63)) >> 32) - ((int64_t)1 << 31));
}

/* Checks the realism parameters against the ranges the integer model needs. */
static bool prv_valid(const km_plant_config_t *c)
{
    const km_plant_real_t *rp = c->real;
    const uint32_t src = (uint32_t)c->supply_r_mohm + (uint32_t)rp->bus_servos * rp->bus_r_mohm;
    return rp->stiff_unm_per_mdeg > 0u && rp->stiff_unm_per_mdeg <= STIFF_MAX &&
           rp->mesh_damp_unm_per_dps <= DAMP_MAX && rp->pwm_period_ns > 0u &&
           rp->dead_ns < rp->pwm_period_ns && rp->min_pulse_ns < rp->pwm_period_ns / 2u &&
           rp->eff_back_pct <= 100u && rp->winding_r_mohm < c->motor_r_mohm && rp->bus_servos > 0u &&
           rp->pot_oversample_log2 <= 8u && rp->stribeck_ddps > 0u && c->load_j_gmm2 >= 1000u &&
           (uint64_t)c->rotor_j_gmm2 * c->gear_ratio * c->gear_ratio >= 1000u &&
           c->viscous_unm_per_dps <= DAMP_MAX && src <= 4u * c->motor_r_mohm && c->gear_eff_pct >= 10u &&
           (uint32_t)rp->winding_r_mohm * rp->tempco_ppm < (1u << 30);
}

/* Speed change per µN·m over `sub` µs on inertia j (g·mm²): 0.1 °/s Q16, Q24. */
static int64_t km_plant_init_real_acc(uint32_t sub, int64_t j)
{
    const int64_t a1 = (((int64_t)sub * DDEG_PER_RAD_X1E5) << 24) / j;
    return a1 * 4096 / 6250000; /* * 65536 / 1e8 */
}

/* True when explicit integration at the sub-step behind acc and kdt is
 * stable: damping removes < 1/2 of a speed per sub-step, and the gear
 * spring's (w dt)^2 < 1/2. */
static bool prv_stable(const km_plant_real_state_t *r, int64_t acc, int64_t b_elec_q32)
{
    const int64_t a8 = acc >> 8;
    const bool damp_ok = (r->damp_q16 >> 8) * a8 < ((int64_t)1 << 39) &&
                         ((b_elec_q32 + r->visc_q16) >> 8) * a8 < ((int64_t)1 << 39);
    const int64_t spring = ((r->stiff * (acc >> 12)) >> 12) * r->kdt;
    return damp_ok && spring < ((int64_t)1 << 47);
}

/* Picks the sub-step (halving config.substep_us until stable) and its gains. */
static bool km_plant_init_real_substep(km_plant_t *p, int64_t b_elec_q32)
{
    const km_plant_config_t *c = p->cfg;
    km_plant_real_state_t *r = &p->r;
    const int64_t ratio = c->gear_ratio;
    const int64_t jm = (int64_t)c->rotor_j_gmm2 * ratio * ratio;
    const int64_t jl = c->load_j_gmm2;
    uint32_t sub = c->substep_us;
    for (;;) {
        r->kdt = ((int64_t)sub << 32) / 1000000;
        r->accm_q24 = km_plant_init_real_acc(sub, jm);
        r->accl_q24 = km_plant_init_real_acc(sub, jl);
        const bool ok = prv_stable(r, r->accm_q24, b_elec_q32) && prv_stable(r, r->accl_q24, 0);
        if (ok || sub == 1u) {
            p->sub_us = sub;
            break;
        }
        sub /= 2u;
    }
    /* torque * acc must stay inside int64 */
    return r->accl_q24 < ((int64_t)1 << 36) && r->accm_q24 < ((int64_t)1 << 36);
}

/* Sensor, bridge, winding and heat gains that do not depend on stability. */
static void km_plant_init_real_gains(km_plant_t *p)
{
    const km_plant_config_t *c = p->cfg;
    const km_plant_real_t *rp = c->real;
    km_plant_real_state_t *r = &p->r;
    const int64_t sub = p->sub_us;
    r->rtemp_q32 = ((int64_t)rp->winding_r_mohm * rp->tempco_ppm << 32) / 1000000000000LL;
    r->heat_q40 = (sub << 40) / ((int64_t)c->thermal_c_mj_per_c * 1000000);
    p->cool_q30 = (sub << 30) / ((int64_t)c->thermal_r_mc_per_w * c->thermal_c_mj_per_c);
    r->adc_gain_q24 =
        c->pot_travel_ddeg > 0 ? ((int64_t)KM_PLANT_POT_ADC_MAX << 24) / (2 * c->pot_travel_ddeg) : 0;
    r->lag_q32 = ((int64_t)rp->pot_window_us << 31) / 1000000; /* half the window */
    r->inv_ws_q16 = ((int64_t)1 << 16) / rp->stribeck_ddps;
    r->noise_pot_q8 = (int32_t)(((int64_t)rp->pot_noise_mlsb << 24) / NOISE_UNIT_SD_X1000);
    r->noise_enc_q8 = (int32_t)(((int64_t)rp->enc_noise_mcount << 24) / NOISE_UNIT_SD_X1000);
    r->dead_pm = (int32_t)((uint32_t)rp->dead_ns * 1000u / rp->pwm_period_ns);
    r->min_pm = (int32_t)((uint32_t)rp->min_pulse_ns * 1000u / rp->pwm_period_ns);
    r->r_fixed_mohm = (int32_t)c->motor_r_mohm - (int32_t)rp->winding_r_mohm;
    r->src_mohm = (int32_t)c->supply_r_mohm + (int32_t)rp->bus_servos * (int32_t)rp->bus_r_mohm;
}

/* Resistance now (the copper at the winding's temperature) and what
 * depends on it; once per km_plant_step. */
static void prv_resistance(km_plant_t *p)
{
    km_plant_real_state_t *r = &p->r;
    const int64_t dt_uc = (int64_t)p->temp_uc - (int64_t)p->cfg->ambient_dc * 100000;
    int64_t mohm = r->r_fixed_mohm + p->cfg->real->winding_r_mohm + prv_mulsh(dt_uc, r->rtemp_q32, 32);
    mohm = mohm < 1 ? 1 : (mohm > 30000 ? 30000 : mohm);
    r->r_mohm = (int32_t)mohm;
    r->g_q16 = (int32_t)(65536000 / r->r_mohm);
    const int32_t rint = (r->src_mohm << 12) / r->r_mohm;
    r->rint_q12 = rint > 4 * 4096 ? 4 * 4096 : rint;
}

/* One draw of the noise generator: near-Gaussian, mean 0, sd 147.8. */
static int32_t prv_noise(km_plant_real_state_t *r)
{
    uint32_t x = r->rng;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    r->rng = x;
    const uint32_t m = x * 2654435769u; /* spread every bit over the four bytes */
    return (int32_t)((m & 0xFFu) + ((m >> 8) & 0xFFu) + ((m >> 16) & 0xFFu) + (m >> 24)) - 510;
}

/* The pot as the board reads it: oversampled noisy ADC, then 0.1°. */
static void prv_sample_pot(km_plant_t *p)
{
    km_plant_real_state_t *r = &p->r;
    const int32_t travel = p->cfg->pot_travel_ddeg;
    if (travel == 0) { /* no pot: the encoder product */
        r->adc = 0;
        r->pos_ddeg = 0;
        return;
    }
    const int64_t lag_q16 = prv_mulsh(r->wl_q16, r->lag_q32, 32);
    /* 0 .. 2 travel on the pot's track, kept within +-travel beyond it */
    const int64_t x_q16 = prv_mulsh(r->th_q32, 1, 16) - lag_q16 + (int64_t)travel * 65536;
    const int64_t x_lo = -(int64_t)travel * 65536;
    const int64_t x_hi = (int64_t)travel * 65536 * 3;
    const int64_t x_in = x_q16 > x_hi ? x_hi : (x_q16 < x_lo ? x_lo : x_q16);
    const int32_t a_q16 = (int32_t)prv_mulsh(x_in, r->adc_gain_q24, 24);
    const uint32_t n = 1u << p->cfg->real->pot_oversample_log2;
    uint32_t sum = 0;
    for (uint32_t i = 0; i < n; i++) {
        const int32_t s = a_q16 + (int32_t)prv_mulsh(prv_noise(r), r->noise_pot_q8, 8);
        const int32_t v = s < 0 ? 0 : (s + 32768) >> 16;
        sum +=
            (uint32_t)(v < 0 ? 0 : (v > (int32_t)KM_PLANT_POT_ADC_MAX ? (int32_t)KM_PLANT_POT_ADC_MAX : v));
    }
    const uint32_t raw = (sum + n / 2u) >> p->cfg->real->pot_oversample_log2;
    r->adc = (uint16_t)raw;
    /* the board's conversion (km_conv_position with the pot's ends at 0 and 4095) */
    const int32_t span = (int32_t)KM_PLANT_POT_ADC_MAX;
    r->pos_ddeg = (int16_t)(((int32_t)raw * 2 * travel + span / 2) / span - travel);
}

/* The encoder: the angle within one turn in counts, with noise, rounded. */
static void prv_sample_encoder(km_plant_t *p)
{
    km_plant_real_state_t *r = &p->r;
    int64_t c_q16 = ((r->enc_q32 >> 16) * ENC_PER_DDEG_Q20) >> 20;
    /* one turn added so that noise below count 0 stays positive */
    c_q16 += prv_mulsh(prv_noise(r), r->noise_enc_q8, 8) + (int64_t)KM_PLANT_ENCODER_COUNTS * 65536;
    r->enc = (uint16_t)((uint64_t)((c_q16 + 32768) >> 16) & (KM_PLANT_ENCODER_COUNTS - 1u));
}

/* pos_ddeg, pos_rem_ndeg and speed_mdps (what the ideal getters read) from the model. */
static void prv_sync(km_plant_t *p)
{
    const km_plant_real_state_t *r = &p->r;
    p->pos_ddeg = prv_ddeg_floor(r->th_q32);
    p->pos_rem_ndeg = (int32_t)(((uint64_t)r->th_q32 & 0xFFFFFFFFu) * 100000000u >> 32);
    p->speed_mdps = (int32_t)prv_mulsh(r->wl_q16, 100, 16);
}

/* km_plant_real.h: gains, sub-step, initial state. */
bool km_plant_init_real(km_plant_t *p)
{
    const km_plant_config_t *c = p->cfg;
    if (!prv_valid(c)) {
        return false;
    }
    const km_plant_real_t *rp = c->real;
    km_plant_real_state_t *r = &p->r;
    const int64_t keg = (int64_t)c->motor_ke_uv_s_rad * c->gear_ratio; /* µV per rad/s at the output */
    r->ke_q32 = (int32_t)((keg * 655360) / 5729578);
    r->kt_q16 = (int32_t)((keg << 16) / 1000);
    if ((keg << 16) / 1000 > INT32_MAX || prv_mulsh(SPEED_MAX_Q16, r->ke_q32, 32) > EMF_MAX_MV) {
        return false;
    }
    r->stiff = (int64_t)rp->stiff_unm_per_mdeg * 100;
    r->damp_q16 = ((int64_t)rp->mesh_damp_unm_per_dps << 16) / 10;
    r->visc_q16 = ((int64_t)c->viscous_unm_per_dps << 16) / 10;
    r->half_play_q32 = ((int64_t)rp->backlash_mdeg << 32) / 200;
    r->mu_fwd_q16 = (int32_t)(((int64_t)(100 - c->gear_eff_pct) << 16) / c->gear_eff_pct);
    r->mu_back_q16 = (int32_t)(((int64_t)(100 - rp->eff_back_pct) << 16) / 100);
    r->src_mohm = (int32_t)c->supply_r_mohm + (int32_t)rp->bus_servos * (int32_t)rp->bus_r_mohm;
    /* electrical damping on the motor side at ambient, µN·m per (0.1 °/s Q16), Q32 */
    const int64_t g_q16 = 65536000 / c->motor_r_mohm;
    const int64_t b_elec_q32 = ((r->ke_q32 * g_q16) >> 16) * r->kt_q16 >> 16;
    if (!km_plant_init_real_substep(p, b_elec_q32)) {
        return false;
    }
    km_plant_init_real_gains(p);
    r->rng = rp->seed != 0u ? rp->seed : 1u;
    r->th_q32 = 0;
    km_plant_real_place(p);
    return true;
}

/* Bridge duty after the minimum pulse and the dead time, per mille. */
static int32_t prv_duty(const km_plant_real_state_t *r, int16_t pwm)
{
    const int32_t d = pwm > 1000 ? 1000 : (pwm < -1000 ? -1000 : pwm);
    int32_t mag = d < 0 ? -d : d;
    if (mag < r->min_pm) {
        mag = 0; /* too short to switch */
    } else if (mag > 1000 - r->min_pm) {
        mag = 1000; /* the off-pulse too short: stays on */
    } else {
        mag -= r->dead_pm;
        mag = mag < 0 ? 0 : mag;
    }
    return d < 0 ? -mag : mag;
}

/* Motor current and bus voltage (as the ideal plant, with R(T), the shared
 * source and the bridge's duty). */
__attribute__((noinline)) static void prv_electrical(km_plant_t *p, km_plant_bridge_t bridge, int32_t d)
{
    km_plant_real_state_t *r = &p->r;
    const int32_t e = (int32_t)prv_mulsh(r->wm_q16, r->ke_q32, 32);
    int32_t bus = p->supply_mv;
    int32_t i = 0;
    int32_t isup = 0;
    if ((p->faults & KM_PLANT_FAULT_MOTOR_OPEN) == 0u) {
        if (bridge == KM_PLANT_DRIVE) {
            if (d != 0) {
                const int32_t gd = r->rint_q12 * d / 1000;
                const int32_t num = (bus << 12) + gd * e;
                const int32_t den = 4096 + gd * d / 1000;
                bus = num / den;
                bus = bus < 0 ? 0 : bus;
            }
            const int32_t vapp = d * bus / 1000;
            i = (int32_t)prv_mulsh(vapp - e, r->g_q16, 16);
            isup = i * d / 1000;
        } else if (bridge == KM_PLANT_BRAKE) {
            i = (int32_t)prv_mulsh(-e, r->g_q16, 16);
        }
    }
    p->current_ma = i;
    p->supply_ma = isup;
    p->bus_mv = bus;
}

/* Torque the gear train puts on the output (µN·m, + = positive): the
 * stiffness beyond the play plus damping; contact only pushes. */
static int64_t prv_mesh(const km_plant_real_state_t *r)
{
    int64_t x = r->defl_q32;
    if (x > r->half_play_q32) {
        x -= r->half_play_q32;
    } else if (x < -r->half_play_q32) {
        x += r->half_play_q32;
    } else {
        return 0;
    }
    const int64_t t = prv_mulsh(x, r->stiff, 32) + prv_mulsh((int64_t)r->wm_q16 - r->wl_q16, r->damp_q16, 32);
    if ((x > 0 && t < 0) || (x < 0 && t > 0)) {
        return 0;
    }
    return t;
}

/* The Stribeck excess at motor-side speed w. */
static int64_t prv_stribeck(const km_plant_t *p, int32_t w)
{
    const int64_t excess = p->cfg->real->stribeck_unm;
    const int64_t ratio_q8 = (prv_abs64(w) * p->r.inv_ws_q16) >> 22; /* |w| / ws * 4 */
    if (excess == 0 || ratio_q8 >= 12 * 256) {
        return 0;
    }
    const int64_t k = ratio_q8 >> 8; /* in quarters of ws */
    const int64_t f = ratio_q8 & 0xFF;
    const int64_t s = k_stribeck_q15[k] + (k_stribeck_q15[k + 1] - k_stribeck_q15[k]) * f / 256;
    return (excess * s) >> 15;
}

/* Friction the gear train opposes to motor-side motion in direction dir:
 * Coulomb, the Stribeck part, and the mesh loss on the torque it carries. */
static int64_t prv_gear_friction(const km_plant_t *p, int64_t ts, int64_t dir, int64_t stribeck)
{
    const bool forward = (ts > 0 && dir > 0) || (ts < 0 && dir < 0);
    const int64_t mu = forward ? p->r.mu_fwd_q16 : p->r.mu_back_q16;
    return (int64_t)p->cfg->coulomb_unm + stribeck + ((prv_abs64(ts) * mu) >> 16);
}

/* A speed after one sub-step under `drive` against friction `fr` (held at
 * rest while |drive| <= fr; friction never reverses the motion). */
static int32_t prv_accelerate(int32_t w, int64_t drive, int64_t fr, int64_t acc_q24)
{
    int64_t net;
    if (w == 0) {
        if (prv_abs64(drive) <= fr) {
            return 0;
        }
        net = drive > 0 ? drive - fr : drive + fr;
    } else {
        net = w > 0 ? drive - fr : drive + fr;
    }
    int64_t wn = w + prv_mulsh(prv_clamp64(net, TORQUE_MAX_UNM), acc_q24, 24);
    if ((w > 0 && wn < 0) || (w < 0 && wn > 0)) {
        wn = 0;
    }
    return (int32_t)prv_clamp64(wn, SPEED_MAX_Q16);
}

/* Motor side: motor torque against the mesh, viscous and gear friction. */
__attribute__((noinline)) static int32_t prv_motor_side(const km_plant_t *p, int64_t ts)
{
    const km_plant_real_state_t *r = &p->r;
    const int32_t w = r->wm_q16;
    const int64_t tm = prv_mulsh(p->current_ma, r->kt_q16, 16);
    const int64_t drive = tm - ts - prv_mulsh(w, r->visc_q16, 32);
    int64_t fr;
    if (w == 0) {
        fr = prv_gear_friction(p, ts, drive, (int64_t)p->cfg->real->stribeck_unm);
    } else {
        fr = prv_gear_friction(p, ts, w, prv_stribeck(p, w));
    }
    return prv_accelerate(w, drive, fr, r->accm_q24);
}

/* sin of an angle in 0.1° (any int32), Q15. */
static int32_t prv_sin_q15(int32_t ddeg)
{
    int32_t a = ddeg % DDEG_PER_TURN;
    a = a < 0 ? a + DDEG_PER_TURN : a;
    int32_t sign = 1;
    if (a >= 1800) {
        a -= 1800;
        sign = -1;
    }
    a = a > 900 ? 1800 - a : a;
    const int32_t k = a / 20;
    const int32_t f = a % 20;
    const int32_t v = k >= 45 ? k_sin_q15[45] : k_sin_q15[k] + (k_sin_q15[k + 1] - k_sin_q15[k]) * f / 20;
    return sign * v;
}

/* Output side: the mesh, the external torque and gravity against the
 * shaft's own friction. */
__attribute__((noinline)) static int32_t prv_output_side(const km_plant_t *p, int64_t ts, int32_t ext_unm)
{
    const km_plant_real_t *rp = p->cfg->real;
    int64_t drive = ts + ext_unm;
    if (rp->gravity_unm != 0u) {
        const int32_t angle = prv_ddeg_floor(p->r.th_q32) - rp->gravity_down_ddeg;
        drive -= prv_mulsh(rp->gravity_unm, prv_sin_q15(angle), 15);
    }
    return prv_accelerate(p->r.wl_q16, drive, (int64_t)rp->out_coulomb_unm, p->r.accl_q24);
}

/* Positions after one sub-step (semi-implicit: the new speeds), end stops,
 * and the encoder's angle within one turn. */
__attribute__((noinline)) static void prv_move(km_plant_t *p, int32_t wm, int32_t wl)
{
    km_plant_real_state_t *r = &p->r;
    const int64_t dl = prv_mulsh(wl, r->kdt, 16);
    const int64_t dm = prv_mulsh(wm, r->kdt, 16);
    /* unsigned: the multi-turn angle wraps like the ideal plant's int32 0.1° */
    int64_t th = (int64_t)((uint64_t)r->th_q32 + (uint64_t)dl);
    int64_t defl = r->defl_q32 + dm - dl;
    const int64_t es = (int64_t)p->cfg->endstop_ddeg << 32;
    if (es > 0 && (th > es || th < -es)) {
        const int64_t stop = th > es ? es : -es;
        defl += th - stop; /* the motor side goes on: the gears take it */
        th = stop;
        wl = (stop > 0 && wl > 0) || (stop < 0 && wl < 0) ? 0 : wl; /* inelastic stop */
    }
    int64_t enc = r->enc_q32 + (int64_t)((uint64_t)th - (uint64_t)r->th_q32);
    const int64_t turn = (int64_t)DDEG_PER_TURN << 32;
    while (enc >= turn) {
        enc -= turn;
    }
    while (enc < 0) {
        enc += turn;
    }
    r->enc_q32 = enc;
    r->th_q32 = th;
    r->defl_q32 = prv_clamp64(defl, DEFL_MAX_Q32);
    r->wm_q16 = wm;
    r->wl_q16 = wl;
}

/* Heat: I^2 R(T) into the winding, Newton cooling to ambient. */
static void prv_thermal(km_plant_t *p)
{
    const int64_t i = p->current_ma;
    const int64_t heat_q30 = (p->r.heat_q40 * p->r.r_mohm) >> 10;
    int64_t t = p->temp_uc;
    t += prv_mulsh(i * i, heat_q30, 30);
    t -= prv_mulsh(t - p->ambient_uc, p->cool_q30, 30);
    p->temp_uc = (int32_t)prv_clamp64(t, TEMP_LIMIT_UC);
}

/* km_plant_real.h: sub-steps, then R(T), the ideal getters' state and the sensors. */
/* One sub-step of the whole model (kept out of line: docs/plant.md "Notes on the code"). */
__attribute__((noinline)) static void prv_substep(km_plant_t *p, const km_plant_input_t *in, int32_t d)
{
    prv_electrical(p, in->bridge, d);
    km_plant_note_peak(p);
    const int64_t ts = prv_mesh(&p->r);
    const int32_t wm = prv_motor_side(p, ts);
    const int32_t wl = prv_output_side(p, ts, in->ext_torque_unm);
    prv_move(p, wm, wl);
    prv_thermal(p);
}

void km_plant_step_real(km_plant_t *p, const km_plant_input_t *in, uint32_t dt_us)
{
    const int32_t d = in->bridge == KM_PLANT_DRIVE ? prv_duty(&p->r, in->pwm) : 0;
    uint32_t t = p->carry_us + dt_us;
    while (t >= p->sub_us) {
        prv_substep(p, in, d);
        t -= p->sub_us;
    }
    p->carry_us = t;
    prv_resistance(p);
    prv_sync(p);
    prv_sample_pot(p);
    prv_sample_encoder(p);
}

/* km_plant_real.h: the model re-seated on the ideal position fields. */
void km_plant_real_place(km_plant_t *p)
{
    km_plant_real_state_t *r = &p->r;
    /* rem (n°, |rem| < 1e8) to Q32 of 0.1°: rem * 2^32 / 1e8 = rem * 2814750 / 2^16 */
    r->th_q32 = (int64_t)p->pos_ddeg * ((int64_t)1 << 32) + prv_mulsh(p->pos_rem_ndeg, 2814750, 16);
    r->defl_q32 = 0;
    /* m°/s to 0.1 °/s Q16: * 655.36 */
    r->wl_q16 = (int32_t)prv_clamp64(prv_mulsh(p->speed_mdps, 42949673, 16), SPEED_MAX_Q16);
    r->wm_q16 = r->wl_q16;
    int32_t within = prv_ddeg_floor(r->th_q32) % DDEG_PER_TURN;
    within = within < 0 ? within + DDEG_PER_TURN : within;
    r->enc_q32 = ((int64_t)within << 32) + (int64_t)((uint64_t)r->th_q32 & 0xFFFFFFFFu);
    prv_resistance(p);
    prv_sync(p);
    prv_sample_pot(p);
    prv_sample_encoder(p);
}
