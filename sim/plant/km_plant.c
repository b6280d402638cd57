/* SPDX-License-Identifier: Apache-2.0 */
/* Simulated servo plant: fixed-point integration of the ideal model
 * (docs/plant.md "The ideal model's integration"). */
#include "km_plant.h"

#include <stddef.h>

#include "km_plant_real.h"

#define NDEG_PER_DDEG 100000000             /* nano-degrees per 0.1° */
#define MDEG_PER_RAD_X1000 57295780LL       /* (180/pi) * 1e6: m°/rad, times 1000 */
#define EMF_MAX_MV 100000                   /* init refuses configs whose EMF at overspeed exceeds this */
#define TEMP_LIMIT_UC 2000000000            /* saturation of the temperature state, µ°C */
#define TORQUE_LIMIT_UNM ((int64_t)1 << 40) /* keeps torque * gain inside int64 */

/* a * b / 2^shift, rounded to nearest, symmetric about zero (so the model
 * behaves identically in both directions). Callers keep |a * b| < 2^62. */
static int64_t prv_mulsh(int64_t a, int64_t b, unsigned shift)
{
    int64_t m = a * b;
    int64_t half = (int64_t)1 << (shift - 1u);
    if (m < 0) {
        return -((-m + half) >> shift);
    }
    return (m + half) >> shift;
}

static int32_t prv_clamp32(int64_t v, int32_t lo, int32_t hi)
{
    if (v < lo) {
        return lo;
    }
    if (v > hi) {
        return hi;
    }
    return (int32_t)v;
}

/* Whether the configuration's values can make a plant at all. */
static bool prv_config_ok(const km_plant_config_t *cfg)
{
    return !(cfg->motor_r_mohm == 0 || cfg->motor_ke_uv_s_rad == 0 || cfg->gear_ratio == 0 ||
             cfg->gear_eff_pct == 0 || cfg->gear_eff_pct > 100 ||
             (uint32_t)cfg->supply_r_mohm > 4u * cfg->motor_r_mohm || cfg->substep_us == 0 ||
             cfg->substep_us > 1000 || cfg->thermal_r_mc_per_w == 0 || cfg->thermal_c_mj_per_c == 0 ||
             cfg->pot_travel_ddeg < 0 || cfg->endstop_ddeg < 0);
}

/* Sub-step length, acceleration and thermal constants for damping b_q16. */
static void prv_init_substep(km_plant_t *p, const km_plant_config_t *cfg, int64_t b_q16, int64_t j_total)
{
    /* Halve the sub-step until the damping removes < 1/2 the speed per sub-step. */
    uint32_t sub = cfg->substep_us;
    int64_t acc_q24;
    for (;;) {
        /* dw[m°/s] = T[µN·m] * dt[µs] * 57.29578 / J[g·mm²] */
        acc_q24 = (((int64_t)sub * MDEG_PER_RAD_X1000) << 24) / (j_total * 1000000);
        if (sub == 1 || prv_mulsh(b_q16, acc_q24, 24) < (1 << 15)) {
            break;
        }
        sub /= 2u;
    }
    p->sub_us = sub;
    p->acc_q24 = acc_q24;
    /* dT[µ°C] = I[mA]^2 * R[mΩ] / 1e6 [mW] * dt[µs] / C[mJ/°C] */
    p->heat_q30 = (((int64_t)cfg->motor_r_mohm * sub) << 30) / ((int64_t)cfg->thermal_c_mj_per_c * 1000000);
    /* dT = -(T - T_amb) * dt / (R_th C), R_th[m°C/W] * C[mJ/°C] = tau in µs */
    p->cool_q30 = ((int64_t)sub << 30) / ((int64_t)cfg->thermal_r_mc_per_w * cfg->thermal_c_mj_per_c);
}

/* The state at power-on: at rest at 0, at ambient temperature. */
static void prv_init_state(km_plant_t *p, const km_plant_config_t *cfg)
{
    p->supply_mv = cfg->supply_mv;
    p->ambient_uc = (int32_t)cfg->ambient_dc * 100000;
    p->faults = 0;
    p->pos_ddeg = 0;
    p->pos_rem_ndeg = 0;
    p->speed_mdps = 0;
    p->current_ma = 0;
    p->supply_ma = 0;
    p->bus_mv = p->supply_mv;
    p->temp_uc = p->ambient_uc;
    p->carry_us = 0;
    p->step_peak_ma = 0;
    p->time_ms = 0;
    p->time_us_part = 0;
}

bool km_plant_init(km_plant_t *p, const km_plant_config_t *cfg)
{
    if (p == NULL || cfg == NULL || !prv_config_ok(cfg)) {
        return false;
    }
    int64_t ratio = cfg->gear_ratio;
    int64_t j_total = (int64_t)cfg->rotor_j_gmm2 * ratio * ratio + cfg->load_j_gmm2;
    if (j_total <= 0) {
        return false;
    }

    /* E[mV] = Ke[µV·s/rad] * ratio * w[m°/s] / 57295780 */
    int64_t ke_q24 = (((int64_t)cfg->motor_ke_uv_s_rad * ratio) << 24) / MDEG_PER_RAD_X1000;
    /* T_out[µN·m] = Kt[µN·m/A] / 1000 * ratio * eff% / 100 * I[mA] */
    int64_t kt_q16 = (((int64_t)cfg->motor_ke_uv_s_rad * ratio * cfg->gear_eff_pct) << 16) / 100000;
    if (ke_q24 <= 0 || ke_q24 > INT32_MAX || kt_q16 <= 0 || kt_q16 > INT32_MAX ||
        prv_mulsh(KM_PLANT_SPEED_MAX_MDPS, ke_q24, 24) > EMF_MAX_MV) {
        return false;
    }
    p->cfg = cfg;
    p->ke_q24 = (int32_t)ke_q24;
    p->kt_q16 = (int32_t)kt_q16;
    p->g_q16 = (int32_t)((1000LL << 16) / cfg->motor_r_mohm);
    p->rint_q12 = (int32_t)(((int64_t)cfg->supply_r_mohm << 12) / cfg->motor_r_mohm);

    /* Damping per m°/s, Q16 µN·m: electrical (Ke Kt / R) plus viscous. */
    p->visc_q16 = ((int64_t)cfg->viscous_unm_per_dps << 16) / 1000;
    int64_t b_q16 = prv_mulsh(prv_mulsh(ke_q24, p->g_q16, 24), kt_q16, 16) + p->visc_q16;
    prv_init_substep(p, cfg, b_q16, j_total);
    prv_init_state(p, cfg);
    /* the realistic model (km_plant_real.c) builds on the state above */
    return cfg->real == NULL || km_plant_init_real(p);
}

/* Electrical: motor current and bus voltage for the bridge state at speed w. */
static void prv_electrical(km_plant_t *p, const km_plant_input_t *in, int32_t w)
{
    int32_t e = (int32_t)prv_mulsh(w, p->ke_q24, 24);
    int32_t bus = p->supply_mv;
    int32_t i = 0;
    int32_t isup = 0;
    if ((p->faults & KM_PLANT_FAULT_MOTOR_OPEN) == 0) {
        if (in->bridge == KM_PLANT_DRIVE) {
            int32_t d = in->pwm > 1000 ? 1000 : (in->pwm < -1000 ? -1000 : in->pwm);
            if (d != 0) {
                /* V_bus = (V_s + g d E) / (1 + g d^2), g = R_int / R, Q12.
                 * |g d| <= 4 * 4096, |E| <= 100 V: fits int32. */
                int32_t gd = p->rint_q12 * d / 1000;
                int32_t num = (bus << 12) + gd * e;
                int32_t den = 4096 + gd * d / 1000;
                bus = num / den;
                if (bus < 0) {
                    bus = 0;
                }
            }
            int32_t vapp = d * bus / 1000;
            i = (int32_t)prv_mulsh(vapp - e, p->g_q16, 16);
            isup = i * d / 1000;
        } else if (in->bridge == KM_PLANT_BRAKE) {
            i = (int32_t)prv_mulsh(-e, p->g_q16, 16);
        }
        /* COAST: open terminals, no current. */
    }
    p->current_ma = i;
    p->supply_ma = isup;
    p->bus_mv = bus;
}

/* Mechanics: new speed after one sub-step (semi-implicit: position uses it). */
static int32_t prv_mechanics(const km_plant_t *p, const km_plant_input_t *in, int32_t w)
{
    const km_plant_config_t *c = p->cfg;
    int64_t tm = prv_mulsh(p->current_ma, p->kt_q16, 16);
    int64_t visc = prv_mulsh(w, p->visc_q16, 16);
    int64_t tdrive = tm + in->ext_torque_unm - visc;
    int64_t tc = c->coulomb_unm;
    int64_t tnet;
    if (w == 0) {
        /* Stiction: at rest, friction holds anything up to Tc. */
        if (tdrive > tc) {
            tnet = tdrive - tc;
        } else if (tdrive < -tc) {
            tnet = tdrive + tc;
        } else {
            return 0;
        }
    } else {
        tnet = w > 0 ? tdrive - tc : tdrive + tc;
    }
    if (tnet > TORQUE_LIMIT_UNM) {
        tnet = TORQUE_LIMIT_UNM;
    } else if (tnet < -TORQUE_LIMIT_UNM) {
        tnet = -TORQUE_LIMIT_UNM;
    }
    int64_t wn = w + prv_mulsh(tnet, p->acc_q24, 24);
    /* Friction stops a shaft; it never reverses it within a sub-step. */
    if ((w > 0 && wn < 0) || (w < 0 && wn > 0)) {
        wn = 0;
    }
    return prv_clamp32(wn, -KM_PLANT_SPEED_MAX_MDPS, KM_PLANT_SPEED_MAX_MDPS);
}

/* Position: integrate w over the sub-step, then apply the hard end-stops. */
static void prv_move(km_plant_t *p, int32_t w)
{
    /* |w| <= 2e6 m°/s, sub <= 1000 µs: |delta| <= 2e9 n°, and |rem| < 1e8. */
    int32_t rem = p->pos_rem_ndeg + w * (int32_t)p->sub_us;
    int32_t q = rem / NDEG_PER_DDEG;
    p->pos_rem_ndeg = rem - q * NDEG_PER_DDEG;
    /* A multi-turn counter wraps like an encoder register (no UB: unsigned add). */
    p->pos_ddeg = (int32_t)((uint32_t)p->pos_ddeg + (uint32_t)q);
    p->speed_mdps = w;

    int32_t es = p->cfg->endstop_ddeg;
    if (es > 0) {
        if (p->pos_ddeg > es || (p->pos_ddeg == es && p->pos_rem_ndeg > 0)) {
            p->pos_ddeg = es;
            p->pos_rem_ndeg = 0;
            if (w > 0) {
                p->speed_mdps = 0; /* inelastic stop */
            }
        } else if (p->pos_ddeg < -es || (p->pos_ddeg == -es && p->pos_rem_ndeg < 0)) {
            p->pos_ddeg = -es;
            p->pos_rem_ndeg = 0;
            if (w < 0) {
                p->speed_mdps = 0;
            }
        }
    }
}

/* Heat: I^2 R into the winding, Newton cooling to ambient. */
static void prv_thermal(km_plant_t *p)
{
    int64_t i = p->current_ma;
    int64_t t = p->temp_uc;
    t += prv_mulsh(i * i, p->heat_q30, 30);
    t -= prv_mulsh(t - p->ambient_uc, p->cool_q30, 30);
    p->temp_uc = prv_clamp32(t, -TEMP_LIMIT_UC, TEMP_LIMIT_UC);
}

void km_plant_step(km_plant_t *p, const km_plant_input_t *in, uint32_t dt_us)
{
    p->step_peak_ma = 0;
    if (p->cfg->real != NULL) {
        km_plant_step_real(p, in, dt_us);
    } else {
        uint32_t t = p->carry_us + dt_us;
        while (t >= p->sub_us) {
            int32_t w = p->speed_mdps;
            prv_electrical(p, in, w);
            km_plant_note_peak(p);
            prv_move(p, prv_mechanics(p, in, w));
            prv_thermal(p);
            t -= p->sub_us;
        }
        p->carry_us = t;
    }
    uint32_t us = p->time_us_part + dt_us;
    p->time_ms += us / 1000u;
    p->time_us_part = us % 1000u;
}

void km_plant_set_supply_mv(km_plant_t *p, int32_t mv)
{
    p->supply_mv = prv_clamp32(mv, 0, 65535);
    p->bus_mv = p->supply_mv;
}

void km_plant_set_ambient_dc(km_plant_t *p, int16_t dc)
{
    p->ambient_uc = (int32_t)dc * 100000;
}

void km_plant_set_temp_dc(km_plant_t *p, int32_t dc)
{
    p->temp_uc = prv_clamp32((int64_t)dc * 100000, -273000000, 2000000000);
}

void km_plant_set_position_ddeg(km_plant_t *p, int32_t ddeg)
{
    p->pos_ddeg = ddeg;
    p->pos_rem_ndeg = 0;
    p->speed_mdps = 0;
    if (p->cfg->real != NULL) {
        km_plant_real_place(p);
    }
}

void km_plant_set_faults(km_plant_t *p, uint32_t faults)
{
    p->faults = faults;
}

/* Whole 0.1° position, remainder rounded to nearest (modulo 2^32, as the
 * multi-turn position wraps). */
static int32_t prv_pos_rounded(const km_plant_t *p)
{
    uint32_t pos = (uint32_t)p->pos_ddeg;
    if (p->pos_rem_ndeg >= NDEG_PER_DDEG / 2) {
        pos++;
    } else if (p->pos_rem_ndeg <= -NDEG_PER_DDEG / 2) {
        pos--;
    }
    return (int32_t)pos;
}

int16_t km_plant_position_ddeg(const km_plant_t *p)
{
    int32_t travel = p->cfg->pot_travel_ddeg;
    if (travel == 0) {
        travel = INT16_MAX;
    }
    if ((p->faults & KM_PLANT_FAULT_POT_OPEN) != 0) {
        return (int16_t)travel;
    }
    if (p->cfg->real != NULL && p->cfg->pot_travel_ddeg != 0) {
        return p->r.pos_ddeg; /* through the ADC, as the board samples it */
    }
    return (int16_t)prv_clamp32(prv_pos_rounded(p), -travel, travel);
}

uint16_t km_plant_pot_adc(const km_plant_t *p)
{
    int32_t travel = p->cfg->pot_travel_ddeg;
    if ((p->faults & KM_PLANT_FAULT_POT_OPEN) != 0) {
        return (uint16_t)KM_PLANT_POT_ADC_MAX;
    }
    if (travel == 0) {
        return 0;
    }
    if (p->cfg->real != NULL) {
        return p->r.adc;
    }
    int32_t x = km_plant_position_ddeg(p) + travel; /* 0 .. 2 travel */
    return (uint16_t)((x * (int32_t)KM_PLANT_POT_ADC_MAX + travel) / (2 * travel));
}

int32_t km_plant_turns_ddeg(const km_plant_t *p)
{
    return prv_pos_rounded(p);
}

/* The true multi-turn angle in µ° (measuring, not a sensor). */
int64_t km_plant_shaft_udeg(const km_plant_t *p)
{
    return (int64_t)p->pos_ddeg * 100000 + p->pos_rem_ndeg / 1000;
}

uint16_t km_plant_encoder_counts(const km_plant_t *p)
{
    if (p->cfg->real != NULL) {
        return p->r.enc;
    }
    /* The angle within one turn, [0, 3600) x 0.1 deg, to the nearest count. */
    int32_t within = p->pos_ddeg % 3600;
    if (within < 0) {
        within += 3600;
    }
    const uint32_t c = ((uint32_t)within * KM_PLANT_ENCODER_COUNTS + 1800u) / 3600u;
    return (uint16_t)(c % KM_PLANT_ENCODER_COUNTS);
}

void km_plant_get_physics(const km_plant_t *p, km_plant_physics_t *out)
{
    out->pos_ddeg = p->pos_ddeg;
    out->pos_rem_ndeg = p->pos_rem_ndeg;
    out->speed_mdps = p->speed_mdps;
    out->temp_uc = p->temp_uc;
    out->supply_mv = p->supply_mv;
    out->ambient_uc = p->ambient_uc;
    out->faults = p->faults;
    out->time_ms = p->time_ms;
}

void km_plant_set_physics(km_plant_t *p, const km_plant_physics_t *in)
{
    p->pos_ddeg = in->pos_ddeg;
    p->pos_rem_ndeg = prv_clamp32(in->pos_rem_ndeg, -(NDEG_PER_DDEG - 1), NDEG_PER_DDEG - 1);
    p->speed_mdps = in->speed_mdps;
    p->temp_uc = in->temp_uc;
    km_plant_set_supply_mv(p, in->supply_mv);
    p->ambient_uc = in->ambient_uc;
    p->faults = in->faults;
    p->time_ms = in->time_ms;
    p->time_us_part = 0;
    p->current_ma = 0;
    p->supply_ma = 0;
    if (p->cfg->real != NULL) {
        km_plant_real_place(p);
    }
}

int32_t km_plant_speed_mdps(const km_plant_t *p)
{
    return p->speed_mdps;
}

int32_t km_plant_speed_dps(const km_plant_t *p)
{
    int32_t w = p->speed_mdps;
    return w >= 0 ? (w + 500) / 1000 : -((-w + 500) / 1000);
}

int32_t km_plant_current_ma(const km_plant_t *p)
{
    return p->current_ma;
}

/* Keeps the largest |current| of the step's sub-steps. */
void km_plant_note_peak(km_plant_t *p)
{
    const int32_t i = p->current_ma < 0 ? -p->current_ma : p->current_ma;
    p->step_peak_ma = i > p->step_peak_ma ? i : p->step_peak_ma;
}

/* The largest |current| of the last step, mA. */
int32_t km_plant_step_peak_ma(const km_plant_t *p)
{
    return p->step_peak_ma;
}

int32_t km_plant_supply_ma(const km_plant_t *p)
{
    return p->supply_ma;
}

int32_t km_plant_voltage_mv(const km_plant_t *p)
{
    return p->bus_mv;
}

int32_t km_plant_temp_dc(const km_plant_t *p)
{
    if ((p->faults & KM_PLANT_FAULT_TEMP_OPEN) != 0) {
        return KM_PLANT_TEMP_OPEN_DC;
    }
    int32_t t = p->temp_uc;
    return t >= 0 ? (t + 50000) / 100000 : -((-t + 50000) / 100000);
}

int32_t km_plant_temp_c(const km_plant_t *p)
{
    if ((p->faults & KM_PLANT_FAULT_TEMP_OPEN) != 0) {
        return KM_PLANT_TEMP_OPEN_DC / 10;
    }
    int32_t t = p->temp_uc;
    return t >= 0 ? (t + 500000) / 1000000 : -((-t + 500000) / 1000000);
}

bool km_plant_at_endstop(const km_plant_t *p)
{
    int32_t es = p->cfg->endstop_ddeg;
    return es > 0 && p->pos_rem_ndeg == 0 && (p->pos_ddeg == es || p->pos_ddeg == -es);
}

uint32_t km_plant_time_ms(const km_plant_t *p)
{
    return p->time_ms;
}
