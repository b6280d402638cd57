/* SPDX-License-Identifier: Apache-2.0 */
/* Step-response benchmark (docs/protocol.md §5.4 0x65/0x66, §5.3 0x46/0x4D,
 * status bit 7): the real control code (control/, through
 * tests/support/km_plant_rig.h: 1 kHz tick, one-tick PWM delay) against the
 * simulated plant (sim/plant), for both products, small and large steps, a
 * move in time and a fastest move, light load, heavy load and a low supply.
 * Prints one table of figures and writes every trace to a CSV file
 * (tools/bench/plot-step draws them). Fails (exit 1) only on a broken run: a
 * refused command, a move that never starts or never moves the shaft, an
 * impossible reading, or a CSV it cannot write; never on a figure.
 *
 * Usage: bench_step [--plant ideal|realistic] [csv-dir]   (else
 * $KM_BENCH_STEP_DIR, else the current directory; CTest runs it in the
 * build tree). Writes <dir>/step_traces.csv. The plant: `realistic` by
 * default (docs/plant.md); `ideal` is the regression case.
 *
 * Each scenario: the plant at rest at the start position, torque on (0x64 =
 * 2), the load applied, HOLD_MS of holding, then the command at t = 0. The
 * tick that runs right after the command is t = 1 ms. Position is the
 * reported 0x46 (0.1 deg, what the servo itself measures); D = target -
 * position at the command; "progress" = (position - start) in D's sign.
 *  - rise time: first tick with progress >= 90 % of |D| minus the first tick
 *    with progress >= 10 % of |D| (ms; "-" if 90 % is never reached);
 *  - overshoot: the largest (position - target) in D's sign over the window,
 *    0 if it never passes the target; in 0.1 deg and in % of |D|;
 *  - settling time: from the command to the first tick after which the
 *    position stays inside target +-0.5 deg (SETTLE_BAND_DDEG) until the end
 *    of the window (ms; "-" if it is outside at the end);
 *  - end (bit 7): the tick at which status bit 7 (running) cleared, i.e.
 *    the servo declared the move over; 0x4D: the rotation time the servo
 *    reports after the move (ms);
 *  - steady-state error: position - target, SS_AFTER_MS after "end" (0.1
 *    deg, signed);
 *  - peak current: the largest |motor current| of the plant from the
 *    command to the end of the window, sampled every 25 us of plant time (a
 *    copy of the plant run ahead in 25 us steps, so every integration
 *    sub-step of the default plant is seen, not only the 1 kHz samples);
 *  - Vmin: the lowest supply terminal voltage over the same span (mV).
 * The window ends SS_AFTER_MS after "end" (or at MAX_MS if bit 7 never
 * clears: a broken run). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../support/km_plant_rig.h"
#include "km_profile.h"

#define HOLD_MS 1500u      /* holding before the command: the integrator takes up the load */
#define LOG_BEFORE_MS 100u /* trace rows before the command */
#define SS_AFTER_MS 1000u  /* steady-state error this long after bit 7 cleared */
#define MAX_MS 6000u       /* a move that has not ended by then is a broken run */
#define SETTLE_BAND_DDEG 5 /* +-0.5 deg */
#define SHADOW_STEP_US 25u /* peak-current sampling of the plant copy */

/* Heavy loads, one at a time so the table says which one costs what:
 * "inertia" adds a 0.01 kg.m^2 load (1 kg at 10 cm; the default reflected
 * rotor inertia is 0.009 kg.m^2, so the total doubles); "torque" holds 0.6
 * N.m against the motion (30 % of the 1.98 N.m stall torque, the load
 * docs/tuning.md sized the integrator for), from before the command. */
#define HEAVY_J_GMM2 10000000u
#define HEAVY_T_UNM 600000
#define LOW_SUPPLY_MV 6000 /* a 2S pack near empty (nominal 7.4 V) */

typedef enum { COND_LIGHT, COND_INERTIA, COND_TORQUE, COND_LOW_SUPPLY, COND_COUNT } prv_cond_t;

static const char *const k_cond_name[COND_COUNT] = {"light", "inertia", "torque", "6.0V"};

typedef struct {
    bool encoder;
    int32_t from; /* 0.1 deg */
    int32_t step; /* 0.1 deg */
    km_move_kind_t kind;
    uint16_t param; /* ms for 0x65, deg/s for 0x66 (0 = fastest) */
    prv_cond_t cond;
    char name[40];
} prv_scenario_t;

typedef struct {
    int32_t rise_ms, settle_ms, end_ms, rot_ms; /* -1 = not reached */
    int32_t overshoot_ddeg, overshoot_pm;       /* pm = per mille of |D| */
    int32_t ss_err_ddeg;
    int32_t peak_ma, vmin_mv;
} prv_figures_t;

static kr_rig_t s_rig;
static const km_plant_config_t *s_base = &km_plant_realistic_config; /* --plant; realistic by default */
static km_plant_config_t s_cfg;                                      /* the plant keeps a pointer to it */
static int32_t s_pos[MAX_MS + 1];                                    /* 0x46 per tick after the command */
static FILE *s_csv;
static int s_broken;

static void prv_broken(const prv_scenario_t *sc, const char *why)
{
    printf("BROKEN RUN %s: %s\n", sc->name, why);
    s_broken = 1;
}

static int32_t prv_abs(int32_t v)
{
    return v < 0 ? -v : v;
}

/* Runs a copy of the plant through the next tick in small steps: the
 * largest |current| and lowest voltage it passes through. */
static void prv_shadow_peak(const kr_rig_t *r, int32_t *peak_ma, int32_t *vmin_mv)
{
    km_plant_t sh = r->plant;
    for (uint32_t us = 0; us < KM_CONTROL_TICK_US; us += SHADOW_STEP_US) {
        km_plant_step(&sh, &r->in, SHADOW_STEP_US);
        const int32_t i = prv_abs(km_plant_current_ma(&sh));
        const int32_t v = km_plant_voltage_mv(&sh);
        *peak_ma = i > *peak_ma ? i : *peak_ma;
        *vmin_mv = v < *vmin_mv ? v : *vmin_mv;
    }
}

static void prv_log(const kr_rig_t *r, const prv_scenario_t *sc, int32_t t_ms, int32_t target)
{
    if (s_csv == NULL) {
        return;
    }
    const int32_t pwm = r->bridge.mode == KM_BRIDGE_PWM ? r->bridge.pwm : 0;
    fprintf(s_csv, "%d,%s,%d,%d,%d,%d,%d,%d,%d\n", t_ms, sc->name, target,
            km_profile_pos_ddeg(&r->ctl.servo.profile), kr_pos(r), km_plant_speed_dps(&r->plant), pwm,
            km_plant_current_ma(&r->plant), km_plant_voltage_mv(&r->plant));
}

/* Plant, params and load for the scenario; torque on and held. */
static bool prv_setup(kr_rig_t *r, const prv_scenario_t *sc)
{
    s_cfg = *s_base;
    if (sc->encoder) { /* as boards/sim-common/km_sim_board.c: no pot, no end stops */
        s_cfg.pot_travel_ddeg = 0;
        s_cfg.endstop_ddeg = 0;
    }
    if (sc->cond == COND_INERTIA) {
        s_cfg.load_j_gmm2 += HEAVY_J_GMM2;
    }
    kr_init_at(r, &s_cfg, sc->from);
    if (sc->encoder) { /* KM-SIM-ENCODER's decoded params (km_sim_product.c) */
        r->encoder = true;
        r->params.variant = KM_VARIANT_ENCODER;
        r->params.travel_min = -32000;
        r->params.travel_max = 32000;
        r->params.angle_min = 0;
        r->params.angle_max = 0;
        km_control_init(&r->ctl, &r->params);
        kr_tick(r);
    }
    if (sc->cond == COND_LOW_SUPPLY) {
        km_plant_set_supply_mv(&r->plant, LOW_SUPPLY_MV);
    }
    if (!kr_torque(r, 2)) {
        prv_broken(sc, "torque on (0x64 = 2) refused");
        return false;
    }
    if (sc->cond == COND_TORQUE) { /* against the motion, like a weight being lifted */
        r->in.ext_torque_unm = sc->step > 0 ? -HEAVY_T_UNM : HEAVY_T_UNM;
    }
    for (uint32_t i = 0; i < HOLD_MS; i++) {
        kr_tick(r);
        if (i >= HOLD_MS - LOG_BEFORE_MS) {
            prv_log(r, sc, (int32_t)i - (int32_t)HOLD_MS + 1, sc->from);
        }
    }
    return true;
}

/* One scenario: command, window, figures. False on a broken run. */
static bool prv_run(const prv_scenario_t *sc, prv_figures_t *f)
{
    kr_rig_t *r = &s_rig;
    memset(f, 0, sizeof *f);
    f->rise_ms = f->settle_ms = f->end_ms = f->rot_ms = -1;
    f->vmin_mv = INT32_MAX;
    if (!prv_setup(r, sc)) {
        return false;
    }
    const int32_t target = sc->from + sc->step;
    const int32_t start = kr_pos(r);
    if (!kr_move(r, sc->kind, (int16_t)target, sc->param)) {
        prv_broken(sc, "move refused (status bit 6)");
        return false;
    }
    const int32_t d = target - start;
    const int32_t sgn = d < 0 ? -1 : 1;
    const int32_t dabs = prv_abs(d);
    if (dabs == 0) {
        prv_broken(sc, "the shaft is already at the target: no step to measure");
        return false;
    }
    int32_t t10 = -1, t90 = -1, last_out = 0, over = 0;
    uint32_t stop = MAX_MS;
    bool started = false;
    for (uint32_t t = 1; t <= stop; t++) {
        prv_shadow_peak(r, &f->peak_ma, &f->vmin_mv);
        kr_tick(r);
        const int32_t pos = kr_pos(r);
        s_pos[t] = pos;
        prv_log(r, sc, (int32_t)t, target);
        const int32_t prog = (pos - start) * sgn;
        if (t10 < 0 && prog * 10 >= dabs) {
            t10 = (int32_t)t;
        }
        if (t90 < 0 && prog * 10 >= dabs * 9) {
            t90 = (int32_t)t;
        }
        over = (pos - target) * sgn > over ? (pos - target) * sgn : over;
        if (prv_abs(pos - target) > SETTLE_BAND_DDEG) {
            last_out = (int32_t)t;
        }
        const int32_t v = km_plant_voltage_mv(&r->plant);
        /* regeneration lifts the bus above the supply, but never to 20 V;
         * the stall current is 2.5 A */
        if (v < 0 || v > 20000 || prv_abs(km_plant_current_ma(&r->plant)) > 10000) {
            prv_broken(sc, "impossible plant reading (voltage or current)");
            return false;
        }
        if (t == 1) {
            started = r->live.running;
        }
        if (f->end_ms < 0 && t > 1 && !r->live.running) {
            f->end_ms = (int32_t)t;
            stop = t + SS_AFTER_MS < MAX_MS ? t + SS_AFTER_MS : MAX_MS;
        }
    }
    if (!started) {
        prv_broken(sc, "status bit 7 not set after an accepted move");
        return false;
    }
    if (f->end_ms < 0) {
        prv_broken(sc, "the move never ended (bit 7 still set)");
        return false;
    }
    if (t10 < 0) {
        prv_broken(sc, "the shaft never moved 10 % of the step");
        return false;
    }
    f->rise_ms = t90 >= 0 ? t90 - t10 : -1;
    f->settle_ms = last_out < (int32_t)stop ? last_out + 1 : -1;
    f->overshoot_ddeg = over;
    f->overshoot_pm = (int32_t)((int64_t)over * 1000 / dabs);
    f->ss_err_ddeg = s_pos[stop] - target;
    f->rot_ms = (int32_t)r->live.rotation_ms;
    return true;
}

/* A value in tenths (0.1 deg, 0.1 V) as "-12.3". */
static const char *prv_tenths(char *buf, size_t n, int32_t ddeg)
{
    (void)snprintf(buf, n, "%s%d.%d", ddeg < 0 ? "-" : "", prv_abs(ddeg) / 10, prv_abs(ddeg) % 10);
    return buf;
}

static const char *prv_ms(char *buf, size_t n, int32_t ms)
{
    if (ms < 0) {
        (void)snprintf(buf, n, "-");
    } else {
        (void)snprintf(buf, n, "%d", ms);
    }
    return buf;
}

static unsigned prv_scenarios(prv_scenario_t *out, unsigned max)
{
    static const int32_t k_steps[] = {50, 900};
    unsigned n = 0;
    for (int enc = 0; enc <= 1; enc++) {
        for (unsigned c = 0; c < COND_COUNT; c++) {
            for (unsigned s = 0; s < 2u; s++) {
                for (int k = 0; k < 2; k++) {
                    if (n >= max) {
                        return n;
                    }
                    prv_scenario_t *sc = &out[n++];
                    sc->encoder = enc != 0;
                    /* pot: from -45 deg; encoder: from 360 deg, a second turn */
                    sc->from = enc ? 3600 : -450;
                    sc->step = k_steps[s];
                    sc->kind = k == 0 ? KM_MOVE_TIME : KM_MOVE_SPEED;
                    sc->param = k == 0 ? 500u : 0u;
                    sc->cond = (prv_cond_t)c;
                    (void)snprintf(sc->name, sizeof sc->name, "%s-%ddeg-%s-%s", enc ? "enc" : "pot",
                                   sc->step / 10, k == 0 ? "t500" : "fast", k_cond_name[c]);
                }
            }
        }
    }
    return n;
}

int main(int argc, char **argv)
{
    const char *dir = getenv("KM_BENCH_STEP_DIR");
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--plant") == 0 && i + 1 < argc) {
            s_base = km_plant_config_named(argv[++i]);
            if (s_base == NULL) {
                printf("BROKEN RUN: --plant %s: not a plant (ideal, realistic)\n", argv[i]);
                return 1;
            }
        } else {
            dir = argv[i];
        }
    }
    if (dir == NULL || dir[0] == '\0') {
        dir = ".";
    }
    char path[512];
    (void)snprintf(path, sizeof path, "%s/step_traces.csv", dir);
    s_csv = fopen(path, "w");
    if (s_csv == NULL) {
        printf("BROKEN RUN: cannot write %s\n", path);
        return 1;
    }
    fprintf(s_csv,
            "t_ms,scenario,target_ddeg,setpoint_ddeg,position_ddeg,speed_dps,pwm,current_ma,voltage_mv\n");

    static prv_scenario_t sc[64];
    const unsigned n = prv_scenarios(sc, sizeof sc / sizeof sc[0]);

    printf(
        "Step response: host (x86) runs of the fixed-point control code (control/, default gains)\n"
        "on the simulated plant (sim/plant, 20 kg.cm class), 1 kHz tick, one-tick PWM delay.\n"
        "Plant: %s. Reproduce: %s [--plant ideal|realistic] [csv-dir]   (ctest -R bench_step -V)\n"
        "t500 = 0x65 move in 500 ms; fast = 0x66 speed 0 (fastest: 0x5D = 360 deg/s, 4000 deg/s^2).\n"
        "light = default load, 7.4 V; inertia = +0.01 kg.m^2 (total x2); torque = 0.6 N.m (30 %% of stall)\n"
        "against the move; 6.0V = default load at a 6.0 V supply. pot starts at -45.0 deg, enc at 360.0 "
        "deg.\n"
        "rise 10-90 %%; settle into +-0.5 deg from the command; end = bit 7 cleared; ss err 1 s after "
        "end.\n\n",
        s_base == &km_plant_ideal_config ? "ideal" : "realistic", argv[0]);
    printf("%-22s %6s %6s %13s %7s %6s %6s %9s %7s\n", "scenario", "rise", "settle", "overshoot", "end",
           "0x4D", "ss err", "peak I", "Vmin");
    printf("%-22s %6s %6s %13s %7s %6s %6s %9s %7s\n", "", "ms", "ms", "deg (%)", "ms", "ms", "deg", "mA",
           "V");
    for (unsigned i = 0; i < n; i++) {
        prv_figures_t f;
        if (!prv_run(&sc[i], &f)) {
            continue;
        }
        char a[16], b[16], c[16], e[16], g[16], h[16], ov[32];
        (void)snprintf(ov, sizeof ov, "%s (%d.%d)", prv_tenths(c, sizeof c, f.overshoot_ddeg),
                       f.overshoot_pm / 10, f.overshoot_pm % 10);
        printf("%-22s %6s %6s %13s %7s %6s %6s %9d %7s\n", sc[i].name, prv_ms(a, sizeof a, f.rise_ms),
               prv_ms(b, sizeof b, f.settle_ms), ov, prv_ms(e, sizeof e, f.end_ms),
               prv_ms(g, sizeof g, f.rot_ms), prv_tenths(h, sizeof h, f.ss_err_ddeg), f.peak_ma,
               prv_tenths(c, sizeof c, (f.vmin_mv + 50) / 100));
    }
    if (fclose(s_csv) != 0) {
        printf("BROKEN RUN: cannot finish %s\n", path);
        return 1;
    }
    printf("\ntraces: %s\n", path);
    return s_broken;
}
