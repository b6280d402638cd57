/* SPDX-License-Identifier: Apache-2.0 */
/* Control-quality benchmark (issue 20; docs/control-quality.md): the eight
 * criteria as figures, each beside its target, measured on the realistic
 * plant (sim/plant, km_plant_realistic_config; docs/plant.md).
 *
 * What runs is what the firmware runs: the simulated product's definition
 * (boards/sim-common/km_sim_product.c), the dispatcher (protocol/km_servo.c)
 * fed real write frames (0x64, 0x65, 0x66, 0x68, 0x6F, 0x70, 0x5B..0x5D,
 * 0x32), control (control/) stepped every 1 ms with the sensor readings of
 * the plant as the simulated boards take them (the pot through the ADC
 * chain; the encoder's counts through km_turn_counter, boards/sim-common/
 * km_sim_board.c), its params re-decoded when a register changes and its
 * live state handed back to the dispatcher, as firmware/app/km_app.c does.
 * The bridge command of one tick drives the plant during the next. All in
 * virtual time: nothing depends on the host's speed.
 *
 * It reports, it does not judge: every figure is printed beside its target
 * with "meets" or "MISSES", and the exit code is 0 whatever the figures.
 * Exit 1 only on a broken run: a command the servo refused (status bit 5 or
 * 6, or control refusing it), a plant configuration that will not start, a
 * move that never starts or never ends, an output it cannot write.
 *
 * Usage: bench_control [--hours H] [--only LIST] [--seed S] [out-dir]   (else $KM_BENCH_CONTROL_DIR,
 * else "."). Writes <dir>/control_traces.csv (tools/bench/plot-control draws one
 * PNG per criterion) and <dir>/control_quality.md (the generated section of
 * docs/control-quality.md; tools/bench/bench-control --doc puts it there).
 * --hours: how long the multi-turn closed loop of criterion 7 runs (1 by
 * default; 24 for the full day, ~25x longer). --only: the criteria to run
 * ("4", "1,4"; the section then has their rows only, no bus figures).
 * --seed: the arrival-jitter generator's start for criterion 4 (12345).
 * bench_control --cost: host CPU time of one 1 ms km_plant_step, ideal and
 * realistic (wall-clock, so it varies with the machine; not a figure of
 * the criteria, and CTest does not run it). */
#include <inttypes.h>
#include <stdarg.h>
#include <time.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "km_app.h"
#include "km_control.h"
#include "km_frame.h"
#include "km_plant.h"
#include "km_servo.h"
#include "km_sim_product.h"
#include "km_turn_counter.h"

#define TICK_US 1000u
#define REC_MAX 40000u    /* recorded ticks of one scenario */
#define SERVO_ID 0u       /* the servo ID's default (0x0F = 0) */
#define ARRIVE_DDEG 5     /* the product's arrive band (gains.arrive_ddeg): 0.5° */
#define MOVE_MAX_MS 8000u /* a move not over by then is a broken run */
#define CHECKS_MAX 40u

/* ---- the bench rig: plant, dispatcher, control ---------------------------- */

typedef struct {
    km_plant_real_t real; /* the realism this scenario runs (a copy it may vary) */
    km_plant_config_t cfg;
    km_plant_t plant;
    km_servo_t servo;
    km_servo_ops_t ops;
    km_control_t ctl;
    km_control_params_t params;
    uint32_t gen;
    km_live_t live;
    km_bridge_t bridge;
    km_plant_input_t in;
    km_turn_counter_t turns;
    bool encoder;
    bool refused;        /* control refused the last request */
    int32_t start_turns; /* encoder: turns the counter starts at (a shaft that has turned before) */
    int32_t ext_unm;     /* external torque on the output, µN·m */
} br_t;

/* One recorded tick. */
typedef struct {
    int64_t shaft_udeg; /* the output shaft, truth, µ° */
    int32_t report;     /* 0x46, 0.1° */
    int32_t speed_mdps; /* the output shaft, truth */
    int32_t pwm;        /* the bridge command, signed (0 = free or brake) */
    int32_t current_ma; /* motor current at the end of the tick */
    int32_t peak_ma;    /* the largest |current| within the tick */
    int32_t target;     /* what the scenario asked, 0.1° */
    bool running;       /* status bit 7 */
} br_sample_t;

typedef struct {
    unsigned criterion;
    char what[128];
    char target[48];
    char measured[160];
    bool meets;
} br_check_t;

static br_t s_b;
static br_sample_t s_rec[REC_MAX];
static uint32_t s_n; /* recorded ticks */
static FILE *s_csv;
static int s_broken;
static br_check_t s_checks[CHECKS_MAX];
static unsigned s_nchecks;
static int32_t s_stall_ma; /* measured on the plant at full PWM */
static int32_t s_stall_unm;
static char s_defects[2048]; /* the issue's defect figures, for the summary */
static unsigned s_hours = 1;
static unsigned s_only; /* --only: criteria as bits 1..8, 0 = all */

/* Marks the run broken (exit 1) and says why. */
static void prv_broken(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    printf("BROKEN RUN: ");
    vprintf(fmt, ap);
    printf("\n");
    va_end(ap);
    s_broken = 1;
}

/* |v| for int32. */
static int32_t prv_abs(int32_t v)
{
    return v < 0 ? -v : v;
}

/* |v| for int64. */
static int64_t prv_abs64(int64_t v)
{
    return v < 0 ? -v : v;
}

/* The dispatcher's hooks: store commits succeed, restarts never come,
 * motion requests go to control as in km_app.c. */
static bool prv_commit(void *ctx, const uint8_t *a, const uint32_t *v, uint8_t n)
{
    (void)ctx;
    (void)a;
    (void)v;
    (void)n;
    return true;
}

/* 0x02 restart: never sent by the bench. */
static void prv_restart(void *ctx)
{
    (void)ctx;
}

/* Typed requests to control, noting a refusal. */
static bool prv_request(void *ctx, const km_request_t *req)
{
    br_t *b = ctx;
    const bool ok = km_control_request(&b->ctl, req, &b->params);
    b->refused = !ok;
    return ok;
}

/* Writes `n` value bytes to register `addr` with command 0x03; false when
 * the servo's short response carries bit 5 or 6 (refused). */
static bool br_write(br_t *b, uint8_t addr, const uint8_t *data, uint8_t n)
{
    km_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = SERVO_ID;
    f.cmd = 0x03;
    f.body[0] = addr;
    memcpy(&f.body[1], data, n);
    f.body_len = (uint8_t)(n + 1u);
    static km_reply_t reply;
    km_servo_handle(&b->servo, &f, &reply);
    if (reply.len < 6u) {
        return addr == 0x11u; /* 0x11 itself may not answer yet */
    }
    return (reply.bytes[4] & 0x60u) == 0u;
}

/* Little-endian 16 bits of v, as the registers are on the wire. */
static void prv_le16(uint8_t *p, int32_t v)
{
    p[0] = (uint8_t)((uint32_t)v & 0xFFu);
    p[1] = (uint8_t)(((uint32_t)v >> 8) & 0xFFu);
}

/* Writes a u8 register. */
static bool br_w8(br_t *b, uint8_t addr, uint8_t v)
{
    return br_write(b, addr, &v, 1u);
}

/* Writes an i16/u16 register. */
static bool br_w16(br_t *b, uint8_t addr, int32_t v)
{
    uint8_t d[2];
    prv_le16(d, v);
    return br_write(b, addr, d, 2u);
}

/* Writes two 16-bit values (0x65, 0x66: target and time or speed). */
static bool br_w16x2(br_t *b, uint8_t addr, int32_t v1, int32_t v2)
{
    uint8_t d[4];
    prv_le16(d, v1);
    prv_le16(&d[2], v2);
    return br_write(b, addr, d, 4u);
}

/* 0x70: control byte, u16, u16. */
static bool br_motor_adv(br_t *b, uint8_t control, int32_t p1, int32_t p2)
{
    uint8_t d[5];
    d[0] = control;
    prv_le16(&d[1], p1);
    prv_le16(&d[3], p2);
    return br_write(b, 0x70u, d, 5u);
}

/* One 1 ms tick, as km_app.c's control tick over the simulated board. */
static void br_tick(br_t *b)
{
    b->in.ext_torque_unm = b->ext_unm;
    km_plant_step(&b->plant, &b->in, TICK_US);
    km_sensors_t s;
    memset(&s, 0, sizeof s);
    s.position = b->encoder ? km_turn_counter_update(&b->turns, km_plant_encoder_counts(&b->plant))
                            : km_plant_position_ddeg(&b->plant);
    s.current_ma = km_plant_current_ma(&b->plant);
    s.voltage_mv = km_plant_voltage_mv(&b->plant);
    s.temperature_c10 = km_plant_temp_dc(&b->plant);
    if (km_servo_params_gen(&b->servo) != b->gen) {
        km_servo_control_params(&b->servo, &b->params);
        b->gen = km_servo_params_gen(&b->servo);
    }
    km_control_step(&b->ctl, &s, &b->params, TICK_US, &b->live, &b->bridge);
    km_servo_set_live(&b->servo, &b->live);
    b->in.bridge = b->bridge.mode == KM_BRIDGE_PWM     ? KM_PLANT_DRIVE
                   : b->bridge.mode == KM_BRIDGE_BRAKE ? KM_PLANT_BRAKE
                                                       : KM_PLANT_COAST;
    b->in.pwm = b->bridge.mode == KM_BRIDGE_PWM ? b->bridge.pwm : 0;
}

/* The realistic plant of the product (pot or encoder) to vary before br_start. */
static void br_prepare(br_t *b, bool encoder)
{
    memset(b, 0, sizeof *b);
    b->encoder = encoder;
    b->cfg = km_plant_realistic_config;
    b->real = km_plant_realistic_params;
    if (encoder) { /* as km_sim_board.c builds the encoder product's plant */
        b->cfg.pot_travel_ddeg = 0;
        b->cfg.endstop_ddeg = 0;
    }
}

/* Plant at rest at `pos` (0.1°), the product booted, 0x11 response level 1
 * (so that every write answers its status). False on a broken start. */
static bool br_start(br_t *b, int32_t pos)
{
    s_n = 0; /* a new record */
    b->cfg.real = &b->real;
    if (!km_plant_init(&b->plant, &b->cfg)) {
        prv_broken("the plant refuses its configuration");
        return false;
    }
    km_plant_set_position_ddeg(&b->plant, pos);
    km_sim_product_select(b->encoder ? KM_SIM_PRODUCT_ENCODER : KM_SIM_PRODUCT_POT);
    b->ops.commit = prv_commit;
    b->ops.restart = prv_restart;
    b->ops.request = prv_request;
    b->ops.ctx = b;
    km_servo_init(&b->servo, km_board_product(), NULL, 1u, &b->ops);
    km_servo_control_params(&b->servo, &b->params);
    b->gen = km_servo_params_gen(&b->servo);
    km_control_init(&b->ctl, &b->params);
    km_turn_counter_init(&b->turns, (uint16_t)KM_PLANT_ENCODER_COUNTS, km_plant_encoder_counts(&b->plant));
    b->turns.turns = b->start_turns;
    b->in.bridge = KM_PLANT_COAST;
    br_tick(b);
    if (!br_w8(b, 0x11u, 0x0Au)) { /* response level 1, idle output brake (the default bit 1) */
        prv_broken("0x11 write refused");
        return false;
    }
    return true;
}

/* ---- recording ----------------------------------------------------------- */

/* Records this tick (truth, 0x46, bridge, current, bit 7). */
static void br_record(const br_t *b, int32_t target)
{
    if (s_n >= REC_MAX) {
        return;
    }
    br_sample_t *r = &s_rec[s_n++];
    r->shaft_udeg = km_plant_shaft_udeg(&b->plant);
    r->report = b->live.position;
    r->speed_mdps = km_plant_speed_mdps(&b->plant);
    r->pwm = b->bridge.mode == KM_BRIDGE_PWM ? b->bridge.pwm : 0;
    r->current_ma = km_plant_current_ma(&b->plant);
    r->peak_ma = km_plant_step_peak_ma(&b->plant);
    r->target = target;
    r->running = b->live.running;
}

/* Runs `ms` ticks, recording each with `target`. */
static void br_run(br_t *b, uint32_t ms, int32_t target)
{
    for (uint32_t i = 0; i < ms; i++) {
        br_tick(b);
        br_record(b, target);
    }
}

/* Writes recorded ticks [from, to) of a series to the CSV, every `every`th. */
static void prv_csv(unsigned crit, const char *series, uint32_t from, uint32_t to, uint32_t every)
{
    if (s_csv == NULL) {
        return;
    }
    for (uint32_t i = from; i < to && i < s_n; i += every) {
        const br_sample_t *r = &s_rec[i];
        fprintf(s_csv, "%u,%s,%u,%.1f,%.4f,%.1f,%.3f,%d,%d,%d,%d\n", crit, series, i - from, r->target / 10.0,
                (double)r->shaft_udeg / 1e6, r->report / 10.0, r->speed_mdps / 1000.0, r->pwm, r->current_ma,
                r->peak_ma, r->running ? 1 : 0);
    }
}

/* A summary row (not a tick): x, y and a reference value. */
static void prv_csv_point(unsigned crit, const char *series, uint32_t x, double y, double ref)
{
    if (s_csv != NULL) {
        fprintf(s_csv, "%u,%s,%u,%.4f,%.4f,0,0,0,0,0,0\n", crit, series, x, ref, y);
    }
}

/* Adds one check: its figure beside its target. */
static void prv_check(unsigned crit, bool meets, const char *what, const char *target, const char *fmt, ...)
{
    if (s_nchecks >= CHECKS_MAX) {
        prv_broken("too many checks");
        return;
    }
    br_check_t *c = &s_checks[s_nchecks++];
    c->criterion = crit;
    c->meets = meets;
    (void)snprintf(c->what, sizeof c->what, "%s", what);
    (void)snprintf(c->target, sizeof c->target, "%s", target);
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(c->measured, sizeof c->measured, fmt, ap);
    va_end(ap);
}

/* Adds a line to the issue-defects summary. */
static void prv_defect(const char *fmt, ...)
{
    const size_t used = strlen(s_defects);
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(s_defects + used, sizeof s_defects - used, fmt, ap);
    va_end(ap);
}

#include "bench_control_bus.h"

/* ---- figures over the record --------------------------------------------- */

/* Mean |current| (mA) and rms over ticks [from, to). */
static void prv_current_stats(uint32_t from, uint32_t to, int32_t *mean_ma, int32_t *rms_ma)
{
    int64_t sum = 0;
    double sq = 0.0;
    const uint32_t n = to > from ? to - from : 1u;
    for (uint32_t i = from; i < to; i++) {
        sum += prv_abs(s_rec[i].current_ma);
        sq += (double)s_rec[i].current_ma * s_rec[i].current_ma;
    }
    *mean_ma = (int32_t)(sum / n);
    double r = sq / n;
    /* square root by Newton's method (no libm in the benches) */
    double x = r > 1.0 ? r : 1.0;
    for (int k = 0; k < 60; k++) {
        x = 0.5 * (x + r / x);
    }
    *rms_ma = (int32_t)(x + 0.5);
}

/* Sign changes of the driven PWM over [from, to) (zeros skipped). */
static uint32_t prv_sign_flips(uint32_t from, uint32_t to)
{
    uint32_t flips = 0;
    int32_t last = 0;
    for (uint32_t i = from; i < to; i++) {
        const int32_t s = s_rec[i].pwm > 0 ? 1 : (s_rec[i].pwm < 0 ? -1 : 0);
        if (s != 0) {
            flips += last != 0 && s != last ? 1u : 0u;
            last = s;
        }
    }
    return flips;
}

/* max - min of 0x46 over [from, to), 0.1°. */
static int32_t prv_report_span(uint32_t from, uint32_t to)
{
    int32_t lo = INT32_MAX, hi = INT32_MIN;
    for (uint32_t i = from; i < to; i++) {
        lo = s_rec[i].report < lo ? s_rec[i].report : lo;
        hi = s_rec[i].report > hi ? s_rec[i].report : hi;
    }
    return hi - lo;
}

/* Mean shaft speed over the 10 ticks ending at i, m°/s. */
static int32_t prv_speed10(uint32_t i)
{
    int64_t sum = 0;
    const uint32_t from = i >= 9u ? i - 9u : 0u;
    for (uint32_t k = from; k <= i; k++) {
        sum += s_rec[k].speed_mdps;
    }
    return (int32_t)(sum / (int64_t)(i - from + 1u));
}

/* Mean shaft position over [from, to), µ°. */
static int64_t prv_mean_shaft(uint32_t from, uint32_t to)
{
    int64_t sum = 0;
    for (uint32_t i = from; i < to; i++) {
        sum += s_rec[i].shaft_udeg;
    }
    return sum / (int64_t)(to > from ? to - from : 1u);
}

/* The largest within-tick |current| over [from, to), mA. */
static int32_t prv_peak(uint32_t from, uint32_t to)
{
    int32_t peak = 0;
    for (uint32_t i = from; i < to && i < s_n; i++) {
        peak = s_rec[i].peak_ma > peak ? s_rec[i].peak_ma : peak;
    }
    return peak;
}

/* Standard deviation of 0x46 over [from, to), in counts. */
static double prv_report_sd(uint32_t from, uint32_t to)
{
    double s1 = 0.0, s2 = 0.0;
    const double n = (double)(to - from);
    for (uint32_t i = from; i < to; i++) {
        s1 += s_rec[i].report;
        s2 += (double)s_rec[i].report * s_rec[i].report;
    }
    const double var = s2 / n - (s1 / n) * (s1 / n);
    double x = var > 1e-9 ? var : 1e-9;
    for (int k = 0; k < 60; k++) {
        x = 0.5 * (x + var / x);
    }
    return var > 1e-9 ? x : 0.0;
}

/* µ° to degrees. */
static double prv_deg(int64_t udeg)
{
    return (double)udeg / 1e6;
}

/* ---- the plant's stall figures ------------------------------------------ */

/* Stall current: the pot plant driven at full PWM against its end stop.
 * Stall torque: the largest opposing torque full PWM still turns the shaft
 * against (bisection, 0.5 s runs from rest). Both at 7.4 V with the bus of
 * the realistic configuration. */
static void prv_measure_stall(void)
{
    br_prepare(&s_b, false);
    s_b.cfg.real = &s_b.real;
    if (!km_plant_init(&s_b.plant, &s_b.cfg)) {
        prv_broken("the plant refuses its configuration");
        return;
    }
    km_plant_set_position_ddeg(&s_b.plant, s_b.cfg.endstop_ddeg);
    const km_plant_input_t full = {KM_PLANT_DRIVE, 1000, 0};
    for (int i = 0; i < 300; i++) {
        km_plant_step(&s_b.plant, &full, TICK_US);
    }
    s_stall_ma = km_plant_current_ma(&s_b.plant);
    int32_t lo = 0, hi = 5000000;
    while (hi - lo > 2000) {
        const int32_t mid = (lo + hi) / 2;
        (void)km_plant_init(&s_b.plant, &s_b.cfg);
        const km_plant_input_t in = {KM_PLANT_DRIVE, 1000, -mid};
        for (int i = 0; i < 500; i++) {
            km_plant_step(&s_b.plant, &in, TICK_US);
        }
        if (km_plant_turns_ddeg(&s_b.plant) > 10) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    s_stall_unm = lo;
}

/* ---- moves ---------------------------------------------------------------- */

typedef struct {
    int32_t end_ms;         /* bit 7 cleared this long after the command (-1: never) */
    int32_t over_mdeg;      /* furthest past the target in the move's direction, truth */
    int32_t clear_err_mdeg; /* |shaft - target| at the tick bit 7 cleared */
    int32_t final_err_mdeg; /* shaft - target `after` ms after bit 7 cleared */
    int32_t peak_ma;        /* the largest |current| from the command on */
    uint32_t cmd_idx;       /* record index of the command's first tick */
} prv_move_t;

/* Bit-7 honesty tallies (criterion 6): unloaded and loaded moves. */
typedef struct {
    unsigned n, outside;
    int32_t worst_mdeg;
} prv_honesty_t;
static prv_honesty_t s_honest[2];

/* Tallies where the shaft was when bit 7 cleared (criterion 6). */
static void prv_honesty(bool loaded, const prv_move_t *m)
{
    prv_honesty_t *h = &s_honest[loaded ? 1 : 0];
    h->n++;
    h->outside += m->clear_err_mdeg > ARRIVE_DDEG * 100 ? 1u : 0u;
    h->worst_mdeg = m->clear_err_mdeg > h->worst_mdeg ? m->clear_err_mdeg : h->worst_mdeg;
    prv_csv_point(6, loaded ? "loaded" : "unloaded", h->n, m->clear_err_mdeg / 1000.0, ARRIVE_DDEG / 10.0);
}

/* Follows the move just commanded (toward `target`, direction `sign`)
 * until bit 7 clears, then `after` ms more. False: broken run. */
static bool prv_follow(br_t *b, int32_t target, int32_t sign, uint32_t after, prv_move_t *m)
{
    memset(m, 0, sizeof *m);
    m->end_ms = -1;
    m->cmd_idx = s_n;
    const int64_t tgt_udeg = (int64_t)target * 100000;
    uint32_t stop = MOVE_MAX_MS;
    for (uint32_t t = 1; t <= stop; t++) {
        br_tick(b);
        br_record(b, target);
        const br_sample_t *r = &s_rec[s_n - 1u];
        const int64_t past = (r->shaft_udeg - tgt_udeg) * sign;
        m->over_mdeg = past / 1000 > m->over_mdeg ? (int32_t)(past / 1000) : m->over_mdeg;
        if (t == 1 && !r->running) {
            prv_broken("status bit 7 not set after an accepted move (target %d)", target);
            return false;
        }
        if (m->end_ms < 0 && !r->running) {
            m->end_ms = (int32_t)t;
            m->clear_err_mdeg = (int32_t)(prv_abs64(r->shaft_udeg - tgt_udeg) / 1000);
            stop = t + after;
        }
    }
    if (m->end_ms < 0) {
        prv_broken("a move to %d never ended (bit 7 still set after %u ms)", target, MOVE_MAX_MS);
        return false;
    }
    m->final_err_mdeg = (int32_t)((s_rec[s_n - 1u].shaft_udeg - tgt_udeg) / 1000);
    m->peak_ma = prv_peak(m->cmd_idx, s_n);
    return true;
}

typedef struct {
    uint8_t cmd;      /* 0x65 time, 0x66 speed */
    int32_t from, to; /* 0.1° */
    int32_t param;    /* ms or °/s (0 = fastest) */
} prv_move_spec_t;

/* Torque on at `from`, settled, then the move; figures in *m. */
static bool prv_move_case(br_t *b, const prv_move_spec_t *sp, prv_move_t *m)
{
    if (!br_start(b, sp->from) || !br_w8(b, 0x64u, 2u)) {
        prv_broken("torque on refused");
        return false;
    }
    br_run(b, 1500u, sp->from);
    if (!br_w16x2(b, sp->cmd, sp->to, sp->param)) {
        prv_broken("move 0x%02X to %d refused", sp->cmd, sp->to);
        return false;
    }
    return prv_follow(b, sp->to, sp->to >= sp->from ? 1 : -1, 1000u, m);
}

/* ---- 1. quiet hold --------------------------------------------------------- */

typedef struct {
    double sd_counts; /* measured sd of the position reading at rest, 0x46 counts */
    int32_t mean_ma, rms_ma;
    double flips_per_s;
    int32_t report_span; /* max - min of 0x46 while holding, counts */
    int32_t shaft_span_mdeg;
} prv_hold_t;

/* ADC noise per sample (1/1000 LSB) that gives the position reading a noise
 * of sigma_x100 / 100 counts of 0x46 (0.1°): the board averages 16 samples
 * (sigma / 4) and one ADC LSB is the pot's span / 4095 (330° / 4095 =
 * 0.081° on the simulated pot). */
static uint16_t prv_pot_noise_for(const br_t *b, int32_t sigma_x100)
{
    const int64_t span_ddeg = 2 * (int64_t)b->cfg.pot_travel_ddeg;
    return (uint16_t)((int64_t)sigma_x100 * 4 * 4095 * 1000 / span_ddeg / 100);
}

#define HOLD_SPOTS 5 /* hold targets 10.0° .. 10.4°: five places between the ADC codes */

/* At rest at target - 10° (the reading's spread measured there), then a
 * move to `target` in 300 ms, 1 s to settle, 4 s measured. */
static bool prv_hold(int32_t sigma_x100, int32_t target, prv_hold_t *h, const char *series)
{
    br_t *b = &s_b;
    br_prepare(b, false);
    b->real.pot_noise_mlsb = prv_pot_noise_for(b, sigma_x100);
    if (!br_start(b, target - 100)) {
        return false;
    }
    br_run(b, 1000u, 0); /* torque off (armed): the shaft at rest, the reading's noise alone */
    h->sd_counts = prv_report_sd(0u, s_n);
    if (!br_w8(b, 0x64u, 2u) || !br_w16x2(b, 0x65u, target, 300)) {
        prv_broken("quiet hold: torque on or 0x65 refused");
        return false;
    }
    prv_move_t m;
    if (!prv_follow(b, target, 1, 1000u, &m)) {
        return false;
    }
    const uint32_t from = s_n;
    br_run(b, 4000u, target);
    prv_current_stats(from, s_n, &h->mean_ma, &h->rms_ma);
    h->flips_per_s = prv_sign_flips(from, s_n) / 4.0;
    h->report_span = prv_report_span(from, s_n);
    int64_t lo = INT64_MAX, hi = INT64_MIN;
    for (uint32_t i = from; i < s_n; i++) {
        lo = s_rec[i].shaft_udeg < lo ? s_rec[i].shaft_udeg : lo;
        hi = s_rec[i].shaft_udeg > hi ? s_rec[i].shaft_udeg : hi;
    }
    h->shaft_span_mdeg = (int32_t)((hi - lo) / 1000);
    if (series != NULL) {
        prv_csv(1, series, from, from + 1000u, 1u);
    }
    return true;
}

/* The holds at HOLD_SPOTS targets: worst (mean, flips, spans) and mean of each. */
static bool prv_hold_spots(int32_t sigma_x100, prv_hold_t *worst, prv_hold_t *mean)
{
    memset(worst, 0, sizeof *worst);
    memset(mean, 0, sizeof *mean);
    for (int32_t k = 0; k < HOLD_SPOTS; k++) {
        char series[32];
        (void)snprintf(series, sizeof series, "sigma%.2f", sigma_x100 / 100.0);
        prv_hold_t h;
        if (!prv_hold(sigma_x100, 100 + k, &h, k == 0 ? series : NULL)) {
            return false;
        }
        worst->mean_ma = h.mean_ma > worst->mean_ma ? h.mean_ma : worst->mean_ma;
        worst->rms_ma = h.rms_ma > worst->rms_ma ? h.rms_ma : worst->rms_ma;
        worst->flips_per_s = h.flips_per_s > worst->flips_per_s ? h.flips_per_s : worst->flips_per_s;
        worst->report_span = h.report_span > worst->report_span ? h.report_span : worst->report_span;
        worst->shaft_span_mdeg =
            h.shaft_span_mdeg > worst->shaft_span_mdeg ? h.shaft_span_mdeg : worst->shaft_span_mdeg;
        mean->sd_counts += h.sd_counts / HOLD_SPOTS;
        mean->mean_ma += h.mean_ma / HOLD_SPOTS;
        mean->rms_ma += h.rms_ma / HOLD_SPOTS;
        mean->flips_per_s += h.flips_per_s / HOLD_SPOTS;
        mean->report_span += h.report_span;
    }
    return true;
}

/* Criterion 1 at noise 0.5 and 1 count (and D2 at 0.25, 0.5, 1); the
 * reading's spread is the mean over the five rest positions. */
static void prv_c1(void)
{
    static const int32_t k_sigma[3] = {25, 50, 100};
    prv_hold_t w[3], m[3];
    for (unsigned k = 0; k < 3u; k++) {
        if (!prv_hold_spots(k_sigma[k], &w[k], &m[k])) {
            return;
        }
        prv_defect(
            "- D2 hold, position noise sigma %.2f count (measured sd of the reading %.2f), worst of %d "
            "targets (mean): %.1f (%.1f) PWM sign flips/s, %d (%d) mA rms, mean current %d (%d) mA, "
            "0x46 span %d counts, shaft span %.3f°\n",
            k_sigma[k] / 100.0, m[k].sd_counts, HOLD_SPOTS, w[k].flips_per_s, m[k].flips_per_s, w[k].rms_ma,
            m[k].rms_ma, w[k].mean_ma, m[k].mean_ma, w[k].report_span, w[k].shaft_span_mdeg / 1000.0);
    }
    for (unsigned k = 1; k < 3u; k++) {
        char what[96];
        (void)snprintf(what, sizeof what, "noise %.1f count: mean hold current, no load (worst of %d)",
                       k_sigma[k] / 100.0, HOLD_SPOTS);
        prv_check(1, w[k].mean_ma < 30, what, "< 30 mA", "%d mA (mean of the %d: %d)", w[k].mean_ma,
                  HOLD_SPOTS, m[k].mean_ma);
        (void)snprintf(what, sizeof what, "noise %.1f count: PWM sign changes (worst)", k_sigma[k] / 100.0);
        prv_check(1, w[k].flips_per_s < 10.0, what, "< 10 /s", "%.1f /s (mean %.1f)", w[k].flips_per_s,
                  m[k].flips_per_s);
        (void)snprintf(what, sizeof what, "noise %.1f count: 0x46 span while holding (worst)",
                       k_sigma[k] / 100.0);
        prv_check(1, w[k].report_span <= 1, what, "<= 1 count", "%d counts", w[k].report_span);
    }
}

/* ---- 2. stiffness ------------------------------------------------------------ */

/* Pot product holding 0° with the stall and current protections off (they
 * would let go of a load held above PWM 600 or 1.5 A for 2 s: 0x32 = 0x05),
 * then loads pushing the shaft positive. */
static bool prv_c2_start(br_t *b)
{
    br_prepare(b, false);
    if (!br_start(b, 0) || !br_w8(b, 0x32u, 0x05u) || !br_w8(b, 0x64u, 2u) || !br_w16x2(b, 0x65u, 0, 200)) {
        prv_broken("stiffness: setup refused");
        return false;
    }
    br_run(b, 1500u, 0);
    return true;
}

/* Criterion 2: steady-state error under 20..80 % of stall torque. */
static void prv_c2_steady(void)
{
    br_t *b = &s_b;
    if (!prv_c2_start(b)) {
        return;
    }
    int32_t worst = 0, err_at[4] = {0, 0, 0, 0};
    for (int pct = 20; pct <= 80; pct += 20) {
        b->ext_unm = (int32_t)((int64_t)s_stall_unm * pct / 100);
        const uint32_t from = s_n;
        br_run(b, 3000u, 0);
        const int32_t err = (int32_t)(prv_mean_shaft(s_n - 1000u, s_n) / 1000);
        worst = prv_abs(err) > prv_abs(worst) ? err : worst;
        err_at[pct / 20 - 1] = err;
        char series[24];
        (void)snprintf(series, sizeof series, "load%d", pct);
        prv_csv(2, series, from, s_n, 10u);
        b->ext_unm = 0;
        br_run(b, 1500u, 0);
    }
    prv_check(2, prv_abs(worst) <= 200, "steady-state error, loads 20..80 % of stall torque (worst)",
              "<= 0.2°", "%.3f° (20 %%: %.3f°, 40 %%: %.3f°, 60 %%: %.3f°, 80 %%: %.3f°)", worst / 1000.0,
              err_at[0] / 1000.0, err_at[1] / 1000.0, err_at[2] / 1000.0, err_at[3] / 1000.0);
}

/* Criterion 2: a 30 % load step, deflection and recovery. */
static void prv_c2_step(void)
{
    br_t *b = &s_b;
    if (!prv_c2_start(b)) {
        return;
    }
    const uint32_t before = s_n > 200u ? s_n - 200u : 0u;
    const int64_t rest = prv_mean_shaft(s_n - 200u, s_n);
    b->ext_unm = (int32_t)((int64_t)s_stall_unm * 30 / 100);
    const uint32_t from = s_n;
    br_run(b, 1500u, 0);
    int64_t peak = 0;
    uint32_t last_out = from;
    for (uint32_t i = from; i < s_n; i++) {
        const int64_t dev = prv_abs64(s_rec[i].shaft_udeg - rest);
        peak = dev > peak ? dev : peak;
        last_out = prv_abs64(s_rec[i].shaft_udeg) > 200000 ? i + 1u : last_out;
    }
    prv_csv(2, "step30", before, s_n, 1u);
    prv_check(2, peak <= 1500000, "load step 30 % of stall: deflection", "<= 1.5°", "%.3f°", prv_deg(peak));
    const bool back = last_out < s_n;
    char took[32] = "not within 1.5 s";
    if (back) {
        (void)snprintf(took, sizeof took, "%u ms", last_out - from);
    }
    prv_check(2, back && last_out - from <= 200u, "load step 30 %: back within 0.2° (and staying)",
              "<= 200 ms", "%s", took);
}

/* ---- 3. point to point (and 6. honest status) -------------------------------- */

static const prv_move_spec_t k_moves[] = {
    {0x65u, -450, 450, 500},  /* 90° in 500 ms */
    {0x65u, -450, -150, 300}, /* 30° in 300 ms */
    {0x65u, 450, -450, 1000}, /* -90° in 1 s */
    {0x66u, -450, 450, 0},    /* 90° fastest */
    {0x66u, -450, -400, 0},   /* 5° fastest */
    {0x66u, 450, 300, 120},   /* -15° at 120 °/s */
};
#define MOVES_N (sizeof k_moves / sizeof k_moves[0])

/* The moves at a load: extra output inertia (x total), an opposing torque
 * (% of stall) or a supply (mV); worst overshoot and, for moves in time,
 * the worst end-time error (per mille of T). */
static bool prv_c3_set(uint32_t inertia_x, int32_t against_pct, int32_t supply_mv, bool loaded, int32_t *over,
                       int32_t *time_pm, const char *series)
{
    *over = 0;
    *time_pm = 0;
    for (unsigned k = 0; k < MOVES_N; k++) {
        br_t *b = &s_b;
        br_prepare(b, false);
        const uint64_t jm = (uint64_t)b->cfg.rotor_j_gmm2 * b->cfg.gear_ratio * b->cfg.gear_ratio;
        b->cfg.load_j_gmm2 += (uint32_t)((jm + b->cfg.load_j_gmm2) * (inertia_x - 1u));
        b->cfg.supply_mv = (uint16_t)supply_mv;
        const prv_move_spec_t *sp = &k_moves[k];
        const int32_t sign = sp->to >= sp->from ? 1 : -1;
        b->ext_unm = (int32_t)(-(int64_t)s_stall_unm * against_pct / 100 * sign);
        prv_move_t m;
        if (!prv_move_case(b, sp, &m)) {
            return false;
        }
        prv_honesty(loaded, &m);
        *over = m.over_mdeg > *over ? m.over_mdeg : *over;
        if (sp->cmd == 0x65u) {
            const int32_t pm = prv_abs(m.end_ms - sp->param) * 1000 / sp->param;
            *time_pm = pm > *time_pm ? pm : *time_pm;
        }
        if (k == 0u && series != NULL) {
            prv_csv(3, series, m.cmd_idx > 100u ? m.cmd_idx - 100u : 0u, s_n, 1u);
        }
    }
    return true;
}

/* Criterion 3: overshoot and end time; the loaded sets feed criterion 6. */
static void prv_c3_overshoot(void)
{
    int32_t over1, t1, over3, t3, o, t;
    if (!prv_c3_set(1u, 0, 7400, false, &over1, &t1, "rated") ||
        !prv_c3_set(3u, 0, 7400, true, &over3, &t3, "inertia3x")) {
        return;
    }
    prv_check(3, over1 <= 300, "overshoot at rated inertia (6 moves, worst)", "<= 0.3°", "%.3f°",
              over1 / 1000.0);
    prv_check(3, over3 <= 1000, "overshoot at 3x inertia (worst)", "<= 1°", "%.3f°", over3 / 1000.0);
    prv_check(3, t1 <= 20, "move in time (0x65): bit 7 clears at T (worst, rated inertia)",
              "within ±2 % of T", "%.1f %% off", t1 / 10.0);
    /* loaded moves for criterion 6: 30 % of stall against, and a 6.0 V supply */
    (void)prv_c3_set(1u, 30, 7400, true, &o, &t, NULL);
    (void)prv_c3_set(1u, 0, 6000, true, &o, &t, NULL);
}

/* 0 -> +90° in 500 ms, at 250 ms a new 0x65 to `second` in 500 ms. */
static bool prv_retarget(int32_t second, prv_move_t *m, const char *series)
{
    br_t *b = &s_b;
    br_prepare(b, false);
    if (!br_start(b, 0) || !br_w8(b, 0x64u, 2u)) {
        prv_broken("retarget: torque on refused");
        return false;
    }
    br_run(b, 1000u, 0);
    const uint32_t cmd = s_n;
    if (!br_w16x2(b, 0x65u, 900, 500)) {
        prv_broken("retarget: first 0x65 refused");
        return false;
    }
    br_run(b, 250u, 900);
    if (!br_w16x2(b, 0x65u, second, 500)) {
        prv_broken("retarget: second 0x65 refused");
        return false;
    }
    const int32_t sign = second >= (int32_t)(s_rec[s_n - 1u].shaft_udeg / 100000) ? 1 : -1;
    if (!prv_follow(b, second, sign, 1000u, m)) {
        return false;
    }
    m->peak_ma = prv_peak(cmd, s_n);
    prv_honesty(true, m);
    prv_csv(3, series, cmd > 100u ? cmd - 100u : 0u, s_n, 1u);
    return true;
}

/* Criterion 3: retarget and reversal mid-move (D1). */
static void prv_c3_retarget(void)
{
    prv_move_t rt, rv;
    if (!prv_retarget(600, &rt, "retarget") || !prv_retarget(-300, &rv, "reversal")) {
        return;
    }
    char tgt[48];
    (void)snprintf(tgt, sizeof tgt, "<= stall current (%d mA)", s_stall_ma);
    prv_check(3, rt.peak_ma <= s_stall_ma, "retarget +90° -> +60° at 250 ms: peak current", tgt, "%d mA",
              rt.peak_ma);
    prv_check(3, prv_abs(rt.end_ms - 500) <= 50, "retarget: new time met (bit 7 clears 500 ms after it)",
              "within ±10 %", "%d ms (%+.1f %%)", rt.end_ms, (rt.end_ms - 500) / 5.0);
    prv_check(3, rv.peak_ma <= s_stall_ma, "reversal +90° -> -30° at 250 ms: peak current", tgt, "%d mA",
              rv.peak_ma);
    prv_check(3, prv_abs(rv.end_ms - 500) <= 50, "reversal: new time met", "within ±10 %", "%d ms (%+.1f %%)",
              rv.end_ms, (rv.end_ms - 500) / 5.0);
    prv_defect("- D1 retarget +90°/500 ms -> +60°/500 ms at 250 ms: overshoot %.3f°, peak current %d mA "
               "(stall %d mA), bit 7 cleared %d ms after the retarget (asked 500)\n",
               rt.over_mdeg / 1000.0, rt.peak_ma, s_stall_ma, rt.end_ms);
    prv_defect("- D1' reversal +90° -> -30° at 250 ms: overshoot %.3f°, peak current %d mA, bit 7 cleared "
               "after %d ms\n",
               rv.over_mdeg / 1000.0, rv.peak_ma, rv.end_ms);
}

/* ---- 4. streaming 0x68 ---------------------------------------------------------- */

typedef struct {
    int32_t vmin_mdps, vmax_mdps, want_mdps;
    int32_t ripple_pm; /* max |v - want| / want, per mille */
    int32_t mean_ma, peak_ma;
    unsigned frames, dropped;
} prv_stream_t;

static uint32_t s_lcg = 12345u;

/* Uniform integer in [-5, 5] (ms of arrival jitter), reproducible. */
static int32_t prv_jitter(void)
{
    s_lcg = s_lcg * 1103515245u + 12345u;
    return (int32_t)((s_lcg >> 16) % 11u) - 5;
}

/* A ramp at 90 °/s from -60° to +60° as 0x68 frames every `period` ms,
 * each arriving up to ±5 ms off its time (never out of order), one frame
 * in 17 dropped (never two in a row) when `rough`. Speed: 10 ms means of
 * the shaft's speed from 300 ms to the last frame. */
static bool prv_stream(uint32_t period, bool rough, prv_stream_t *f, const char *series)
{
    br_t *b = &s_b;
    br_prepare(b, false);
    if (!br_start(b, -600) || !br_w8(b, 0x64u, 2u)) {
        prv_broken("stream: torque on refused");
        return false;
    }
    br_run(b, 1000u, -600);
    memset(f, 0, sizeof *f);
    const int32_t step = (int32_t)(period * 9u / 10u); /* 0.1° per frame at 90 °/s */
    const uint32_t n = 1200u / (uint32_t)step;
    const uint32_t t0 = s_n;
    uint32_t t = 0, last_arrival = 0, k = 1;
    uint32_t arrive = period + (uint32_t)(rough ? prv_jitter() : 0);
    int32_t target = -600;
    while (k <= n || t < last_arrival + 1000u) {
        while (k <= n && arrive <= t) {
            const bool drop = rough && k % 17u == 8u;
            if (!drop) {
                target = -600 + (int32_t)k * step;
                if (!br_w16(b, 0x68u, target)) {
                    prv_broken("stream: 0x68 refused");
                    return false;
                }
                f->frames++;
            } else {
                f->dropped++;
            }
            last_arrival = arrive;
            k++;
            const int32_t due = (int32_t)(k * period) + (rough ? prv_jitter() : 0);
            arrive = due < (int32_t)last_arrival ? last_arrival : (uint32_t)due;
        }
        br_tick(b);
        br_record(b, target);
        t++;
    }
    f->want_mdps = step * 100000 / (int32_t)period;
    f->vmin_mdps = INT32_MAX;
    f->vmax_mdps = INT32_MIN;
    for (uint32_t i = t0 + 300u; i < t0 + last_arrival; i++) {
        const int32_t v = prv_speed10(i);
        f->vmin_mdps = v < f->vmin_mdps ? v : f->vmin_mdps;
        f->vmax_mdps = v > f->vmax_mdps ? v : f->vmax_mdps;
    }
    const int32_t dev = prv_abs(f->vmax_mdps - f->want_mdps) > prv_abs(f->vmin_mdps - f->want_mdps)
                            ? prv_abs(f->vmax_mdps - f->want_mdps)
                            : prv_abs(f->vmin_mdps - f->want_mdps);
    f->ripple_pm = dev * 1000 / f->want_mdps;
    int32_t rms;
    prv_current_stats(t0 + 300u, t0 + last_arrival, &f->mean_ma, &rms);
    f->peak_ma = prv_peak(t0 + 300u, t0 + last_arrival);
    prv_csv(4, series, t0, s_n, 1u);
    return true;
}

/* Criterion 4: 50 and 100 Hz streams with jitter and drops (D2b). */
static void prv_c4(void)
{
    prv_stream_t f50, f100, clean;
    if (!prv_stream(20u, true, &f50, "50Hz") || !prv_stream(10u, true, &f100, "100Hz") ||
        !prv_stream(20u, false, &clean, "50Hz-clean")) {
        return;
    }
    const prv_stream_t *fs[2] = {&f50, &f100};
    static const char *const k_name[2] = {"50 Hz", "100 Hz"};
    for (unsigned i = 0; i < 2u; i++) {
        char what[96];
        (void)snprintf(what, sizeof what, "0x68 %s ±5 ms, 1 frame in 17 dropped: speed ripple", k_name[i]);
        prv_check(4, fs[i]->ripple_pm <= 100, what, "<= ±10 %", "±%.1f %% (%.1f..%.1f °/s, stream %.1f)",
                  fs[i]->ripple_pm / 10.0, fs[i]->vmin_mdps / 1000.0, fs[i]->vmax_mdps / 1000.0,
                  fs[i]->want_mdps / 1000.0);
        (void)snprintf(what, sizeof what, "0x68 %s: current pulses over the steady current", k_name[i]);
        prv_check(4, fs[i]->peak_ma * 2 <= fs[i]->mean_ma * 3, what, "<= 1.5x",
                  "%.1fx (peak %d mA, mean %d mA)",
                  (double)fs[i]->peak_ma / (fs[i]->mean_ma > 0 ? fs[i]->mean_ma : 1), fs[i]->peak_ma,
                  fs[i]->mean_ma);
    }
    prv_defect(
        "- D2b 0x68 stream 50 Hz ±5 ms, %u frames, %u dropped: shaft speed %.1f..%.1f °/s (stream %.1f), "
        "current peak %d mA over a mean of %d mA (the same stream on time, none dropped: %.1f..%.1f °/s, "
        "peak %d mA)\n",
        f50.frames, f50.dropped, f50.vmin_mdps / 1000.0, f50.vmax_mdps / 1000.0, f50.want_mdps / 1000.0,
        f50.peak_ma, f50.mean_ma, clean.vmin_mdps / 1000.0, clean.vmax_mdps / 1000.0, clean.peak_ma);
}

/* ---- 5. limits ------------------------------------------------------------------ */

#define C5_TORQUE 700
#define C5_CURRENT 1000
#define C5_SPEED 180

/* Waits for the move just sent to end (bit 7), up to MOVE_MAX_MS. */
static bool prv_wait_end(br_t *b, int32_t target, uint32_t after)
{
    br_tick(b);
    br_record(b, target);
    for (uint32_t t = 0; t < MOVE_MAX_MS && s_rec[s_n - 1u].running; t++) {
        br_tick(b);
        br_record(b, target);
    }
    br_run(b, after, target);
    return !s_rec[s_n - 1u].running;
}

/* 0x5B = 700, 0x5C = 1000 mA, 0x5D = 180 °/s; a fastest move reversed
 * half-way, a move in time faster than 0x5D allows, a hold against half
 * the stall torque (1.5 s: below the stall protection's 2 s). */
static bool prv_c5_run(br_t *b)
{
    br_prepare(b, false);
    if (!br_start(b, 0) || !br_w16(b, 0x5Bu, C5_TORQUE) || !br_w16(b, 0x5Cu, C5_CURRENT) ||
        !br_w16(b, 0x5Du, C5_SPEED) || !br_w8(b, 0x64u, 2u)) {
        prv_broken("limits: setup refused");
        return false;
    }
    br_run(b, 500u, 0);
    bool ok = br_w16x2(b, 0x66u, 900, 0);
    br_run(b, 300u, 900);
    ok = ok && br_w16x2(b, 0x66u, -600, 0) && prv_wait_end(b, -600, 300u);
    ok = ok && br_w16x2(b, 0x65u, 600, 300) && prv_wait_end(b, 600, 300u);
    b->ext_unm = -s_stall_unm / 2;
    br_run(b, 1500u, 600);
    b->ext_unm = 0;
    br_run(b, 500u, 600);
    if (!ok) {
        prv_broken("limits: a move was refused or never ended");
    }
    return ok;
}

/* Criterion 5: 0x5C, 0x5B and 0x5D over the limits run. */
static void prv_c5(void)
{
    br_t *b = &s_b;
    if (!prv_c5_run(b)) {
        return;
    }
    uint32_t run = 0, longest = 0;
    int32_t pwm_max = 0, v_max = 0, i_max = 0;
    for (uint32_t i = 0; i < s_n; i++) {
        run = s_rec[i].peak_ma * 10 > C5_CURRENT * 11 ? run + 1u : 0u;
        longest = run > longest ? run : longest;
        pwm_max = prv_abs(s_rec[i].pwm) > pwm_max ? prv_abs(s_rec[i].pwm) : pwm_max;
        v_max = prv_abs(prv_speed10(i)) > v_max ? prv_abs(prv_speed10(i)) : v_max;
        i_max = s_rec[i].peak_ma > i_max ? s_rec[i].peak_ma : i_max;
    }
    prv_csv(5, "limits", 0u, s_n, 1u);
    prv_check(5, longest <= 5u, "0x5C = 1000 mA: longest time above it by > 10 %, braking included",
              "<= 5 ms", "%u ms (peak %d mA)", longest, i_max);
    prv_check(5, pwm_max <= C5_TORQUE, "0x5B = 700: largest PWM driven", "<= 700", "%d", pwm_max);
    prv_check(5, v_max <= C5_SPEED * 1000, "0x5D = 180 °/s: fastest shaft (10 ms mean)", "<= 180 °/s",
              "%.1f °/s", v_max / 1000.0);
}

/* ---- 6. honest status ------------------------------------------------------------ */

/* Criterion 6: the bit-7 tallies of the moves run so far. */
static void prv_c6(void)
{
    static const char *const k_what[2] = {
        "bit 7 clears only inside ±0.5°: unloaded moves (criterion 3's)",
        "bit 7 clears only inside ±0.5°: loaded moves (3x inertia, 30 % stall against, 6.0 V, retargets)"};
    for (unsigned k = 0; k < 2u; k++) {
        const prv_honesty_t *h = &s_honest[k];
        prv_check(6, h->n > 0u && h->outside == 0u, k_what[k], "every move", "%u of %u outside (worst %.3f°)",
                  h->outside, h->n, h->worst_mdeg / 1000.0);
    }
}

/* ---- 7. multi-turn ---------------------------------------------------------------- */

/* 0x46 minus the true shaft angle, 0.1° (the encoder product's zero is the
 * plant's 0 when it boots there). */
static int32_t prv_drift(const br_t *b)
{
    const int64_t truth = km_plant_shaft_udeg(&b->plant);
    const int64_t truth_ddeg = (truth >= 0 ? truth + 50000 : truth - 50000) / 100000;
    return (int32_t)((int64_t)b->live.position - truth_ddeg);
}

/* The closed loop: 0x6F at 360 °/s for s_hours, then stopped; 0x46 against
 * the truth every simulated minute. */
static void prv_c7_loop(void)
{
    br_t *b = &s_b;
    br_prepare(b, true);
    if (!br_start(b, 0) || !br_w16(b, 0x6Fu, 360)) {
        prv_broken("multi-turn: 0x6F refused");
        return;
    }
    int32_t worst = 0;
    const uint32_t minutes = s_hours * 60u;
    for (uint32_t min = 1; min <= minutes; min++) {
        for (uint32_t i = 0; i < 60000u; i++) {
            br_tick(b);
        }
        const int32_t d = prv_drift(b);
        worst = prv_abs(d) > prv_abs(worst) ? d : worst;
        prv_csv_point(7, "loop", min, d / 10.0, 0.0);
    }
    const int64_t turns = km_plant_shaft_udeg(&b->plant) / 360000000;
    (void)br_w16(b, 0x6Fu, 0);
    br_run(b, 1000u, 0);
    const int32_t end = prv_drift(b);
    worst = prv_abs(end) > prv_abs(worst) ? end : worst;
    prv_check(7, prv_abs(worst) < 1800, "turn count, closed loop 0x6F 360 °/s (0x46 - true angle, worst)",
              "no drift", "%.1f° after %u h (%" PRId64 " turns)", worst / 10.0, s_hours, turns);
}

/* 24 h of the turn-count path alone: the plant's encoder (noise and all)
 * sampled every 1 ms on a shaft turning at 360 °/s, through km_turn_counter
 * (the code the encoder board runs); the control loop is not in it. */
static void prv_c7_day(void)
{
    br_t *b = &s_b;
    br_prepare(b, true);
    b->cfg.real = &b->real;
    if (!km_plant_init(&b->plant, &b->cfg)) {
        prv_broken("the plant refuses its configuration");
        return;
    }
    km_turn_counter_t tc;
    km_turn_counter_init(&tc, (uint16_t)KM_PLANT_ENCODER_COUNTS, km_plant_encoder_counts(&b->plant));
    int32_t worst = 0, pos = 0;
    for (uint32_t ms = 1; ms <= 24u * 3600u * 1000u; ms++) {
        pos = (int32_t)((uint64_t)ms * 36u / 10u); /* 3.6 x 0.1° per ms */
        km_plant_set_position_ddeg(&b->plant, pos);
        const int32_t d = km_turn_counter_update(&tc, km_plant_encoder_counts(&b->plant)) - pos;
        worst = prv_abs(d) > prv_abs(worst) ? d : worst;
        if (ms % 3600000u == 0u) {
            prv_csv_point(7, "day", ms / 3600000u, worst / 10.0, 0.0);
        }
    }
    prv_check(7, prv_abs(worst) < 1800, "turn count, 24 h at 360 °/s: encoder + km_turn_counter (worst)",
              "no drift", "%.1f° after 24 h (86400 turns)", worst / 10.0);
}

typedef struct {
    int32_t mean_ma, rms_ma, shaft_span_mdeg;
} prv_turn_hold_t;

/* Holding (0x64 = 2, no load) at a turn count; the PWM of 3 s into pwm[]. */
static bool prv_hold_turns(int32_t turns, int32_t *pwm, uint32_t n, prv_turn_hold_t *h)
{
    br_t *b = &s_b;
    br_prepare(b, true);
    b->start_turns = turns;
    if (!br_start(b, 900 + turns * 3600) || !br_w8(b, 0x64u, 2u)) {
        prv_broken("hold at %d turns: torque on refused", turns);
        return false;
    }
    br_run(b, n, 0);
    int64_t lo = INT64_MAX, hi = INT64_MIN;
    for (uint32_t i = 0; i < n; i++) {
        pwm[i] = s_rec[i].pwm;
        lo = s_rec[i].shaft_udeg < lo ? s_rec[i].shaft_udeg : lo;
        hi = s_rec[i].shaft_udeg > hi ? s_rec[i].shaft_udeg : hi;
    }
    prv_current_stats(0u, n, &h->mean_ma, &h->rms_ma);
    h->shaft_span_mdeg = (int32_t)((hi - lo) / 1000);
    if (turns == 0 || turns == 250 || turns == 298 || turns == 596500) { /* the plot's four */
        char series[24];
        (void)snprintf(series, sizeof series, "hold%d", turns);
        prv_csv(7, series, 0u, 400u, 1u);
    }
    return true;
}

/* The same hold (angle within the turn, noise) at growing turn counts,
 * compared tick by tick with the hold at turn 0. */
static void prv_c7_same_hold(void)
{
    static int32_t pwm0[3000], pwm1[3000];
    static const int32_t k_turns[] = {1, 10, 100, 250, 298, 1000, 100000, 596500};
    prv_turn_hold_t h0, h;
    if (!prv_hold_turns(0, pwm0, 3000u, &h0)) {
        return;
    }
    int32_t same_up_to = 0, first_bad = -1, max_diff = 0;
    uint32_t ndiff = 0;
    prv_turn_hold_t bad = h0;
    for (unsigned k = 0; k < sizeof k_turns / sizeof k_turns[0]; k++) {
        if (!prv_hold_turns(k_turns[k], pwm1, 3000u, &h)) {
            return;
        }
        uint32_t n = 0;
        for (uint32_t i = 0; i < 3000u; i++) {
            const int32_t d = prv_abs(pwm1[i] - pwm0[i]);
            n += d != 0 ? 1u : 0u;
            max_diff = first_bad < 0 && d > max_diff ? d : max_diff;
        }
        if (n == 0u && first_bad < 0) {
            same_up_to = k_turns[k];
        } else if (first_bad < 0) {
            first_bad = k_turns[k];
            ndiff = n;
            bad = h;
        }
    }
    char got[160];
    if (first_bad < 0) {
        (void)snprintf(got, sizeof got, "identical PWM, tick for tick, at every count up to %d turns",
                       same_up_to);
    } else {
        (void)snprintf(
            got, sizeof got,
            "identical up to %d turns; from %d turns the PWM differs in %u of 3000 ticks (by up to %d), "
            "mean |I| %d vs %d mA",
            same_up_to, first_bad, ndiff, max_diff, bad.mean_ma, h0.mean_ma);
    }
    prv_check(7, first_bad < 0, "hold at 0 .. 596500 turns (3 s each, same angle and noise)",
              "the same holding", "%s", got);
}

/* Through the int32 wrap of 0x46 (+214748364.7°): 0x6F at 360 °/s from
 * 2 turns below it for 10 s, then stop and hold 2 s. */
static void prv_c7_wrap(void)
{
    br_t *b = &s_b;
    br_prepare(b, true);
    b->start_turns = 596522;
    if (!br_start(b, 900 + 596522 * 3600) || !br_w16(b, 0x6Fu, 360)) {
        prv_broken("wrap: 0x6F refused");
        return;
    }
    br_run(b, 10000u, 0);
    int32_t step_max = 0;
    uint32_t wrap_at = 0;
    for (uint32_t i = 1; i < s_n; i++) {
        const int32_t d = (int32_t)((uint32_t)s_rec[i].report - (uint32_t)s_rec[i - 1u].report);
        step_max = prv_abs(d) > step_max ? prv_abs(d) : step_max;
        wrap_at = s_rec[i - 1u].report > 0 && s_rec[i].report < 0 ? i : wrap_at;
    }
    int32_t vlo = INT32_MAX, vhi = INT32_MIN;
    for (uint32_t i = wrap_at > 300u ? wrap_at - 300u : 10u; i < wrap_at + 300u && i < s_n; i++) {
        vlo = prv_speed10(i) < vlo ? prv_speed10(i) : vlo;
        vhi = prv_speed10(i) > vhi ? prv_speed10(i) : vhi;
    }
    prv_csv(7, "wrap", wrap_at > 500u ? wrap_at - 500u : 0u, wrap_at + 500u, 1u);
    const bool ok = br_w16(b, 0x6Fu, 0) && br_w8(b, 0x64u, 2u);
    br_run(b, 500u, 0);
    const uint32_t from = s_n;
    br_run(b, 1500u, 0);
    int64_t lo = INT64_MAX, hi = INT64_MIN;
    for (uint32_t i = from; i < s_n; i++) {
        lo = s_rec[i].shaft_udeg < lo ? s_rec[i].shaft_udeg : lo;
        hi = s_rec[i].shaft_udeg > hi ? s_rec[i].shaft_udeg : hi;
    }
    const bool meets = ok && wrap_at > 0u && step_max <= 100 && vlo >= 288000 && hi - lo <= 500000;
    prv_check(7, meets, "0x46 through +2^31 x 0.1° at 360 °/s, then hold", "defined wrap, motion unaffected",
              "%s at tick %u, largest step %d, speed %.0f..%.0f °/s around it, hold span %.3f°",
              wrap_at > 0u ? "wraps to -2^31" : "never wraps", wrap_at, step_max, vlo / 1000.0, vhi / 1000.0,
              prv_deg(hi - lo));
}

/* ---- 8. low speed and counted runs ------------------------------------------------- */

/* 0x6F at dps for 6 s; the worst 200 ms mean from 1 s on, per mille off. */
static bool prv_c8_speed(int32_t dps, int32_t *worst_pm, const char *series)
{
    br_t *b = &s_b;
    br_prepare(b, true);
    if (!br_start(b, 0) || !br_w16(b, 0x6Fu, dps)) {
        prv_broken("0x6F %d refused", dps);
        return false;
    }
    br_run(b, 6000u, 0);
    *worst_pm = 0;
    for (uint32_t w = 1000; w + 200u <= s_n; w += 200u) {
        int64_t sum = 0;
        for (uint32_t i = w; i < w + 200u; i++) {
            sum += s_rec[i].speed_mdps;
        }
        const int32_t pm = (int32_t)prv_abs64(sum / 200 - dps * 1000) / prv_abs(dps);
        *worst_pm = pm > *worst_pm ? pm : *worst_pm;
    }
    prv_csv(8, series, 0u, s_n, 5u);
    return true;
}

/* A counted 0x70 run at 360 °/s, brake after; the stop's error (m°). */
static bool prv_c8_run(uint8_t control, int32_t p1, int32_t expect_ddeg, int32_t *err_mdeg,
                       const char *series)
{
    br_t *b = &s_b;
    br_prepare(b, true);
    if (!br_start(b, 0) || !br_motor_adv(b, control, p1, 360)) {
        prv_broken("0x70 0x%02X refused", control);
        return false;
    }
    if (!prv_wait_end(b, expect_ddeg, 1000u)) {
        prv_broken("0x70 0x%02X never ended", control);
        return false;
    }
    *err_mdeg = (int32_t)((s_rec[s_n - 1u].shaft_udeg - (int64_t)expect_ddeg * 100000) / 1000);
    prv_csv(8, series, 0u, s_n, 2u);
    return true;
}

/* Criterion 8: 0x6F at +-5 deg/s, 0x70 angle and turns runs. */
static void prv_c8(void)
{
    int32_t up, down, angle, turns;
    if (!prv_c8_speed(5, &up, "speed+5") || !prv_c8_speed(-5, &down, "speed-5") ||
        !prv_c8_run(0x26u, 720, 7200, &angle, "angle720") ||
        !prv_c8_run(0x36u, 25, 9000, &turns, "turns2.5")) {
        return;
    }
    prv_check(8, up <= 200, "0x6F +5 °/s: 200 ms means from 1 s to 6 s (worst)", "within ±20 %",
              "%.1f %% off", up / 10.0);
    prv_check(8, down <= 200, "0x6F -5 °/s (worst)", "within ±20 %", "%.1f %% off", down / 10.0);
    prv_check(8, prv_abs(angle) <= 2000, "0x70 angle run 720° at 360 °/s, brake: stop", "within ±2°",
              "%+.2f°", angle / 1000.0);
    prv_check(8, prv_abs(turns) <= 2000, "0x70 turns run 2.5 turns at 360 °/s, brake: stop", "within ±2°",
              "%+.2f°", turns / 1000.0);
}

/* ---- output --------------------------------------------------------------------- */

static const char *const k_criterion[9] = {
    "",
    "quiet hold",
    "stiffness",
    "point to point",
    "streaming 0x68",
    "limits",
    "honest status",
    "multi-turn",
    "low speed and counted runs",
};

/* How many checks meet their target. */
static unsigned prv_met(void)
{
    unsigned met = 0;
    for (unsigned i = 0; i < s_nchecks; i++) {
        met += s_checks[i].meets ? 1u : 0u;
    }
    return met;
}

/* The table on stdout, then the defect figures. */
static void prv_print(void)
{
    printf("%-3s %-74s %-34s %s\n", "#", "check", "target", "measured");
    unsigned last = 0;
    for (unsigned i = 0; i < s_nchecks; i++) {
        const br_check_t *c = &s_checks[i];
        if (c->criterion != last) {
            printf("-- %u. %s\n", c->criterion, k_criterion[c->criterion]);
            last = c->criterion;
        }
        printf("%-3u %-74s %-34s %s  [%s]\n", c->criterion, c->what, c->target, c->measured,
               c->meets ? "meets" : "MISSES");
    }
    printf(
        "\n%u of %u checks meet their target.\n\nThe issue's defects, measured on this plant:\n%s\nOver the "
        "bus:\n%s",
        prv_met(), s_nchecks, s_defects, s_bus_text);
}

/* A table cell: '|' would end it, so it is escaped. */
static void prv_md_cell(FILE *f, const char *text)
{
    fputs("| ", f);
    for (const char *c = text; *c != '\0'; c++) {
        if (*c == '|') {
            fputc('\\', f);
        }
        fputc(*c, f);
    }
    fputc(' ', f);
}

/* The generated section of docs/control-quality.md. */
static bool prv_markdown(const char *dir)
{
    char path[512];
    (void)snprintf(path, sizeof path, "%s/control_quality.md", dir);
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        return false;
    }
    fprintf(f,
            "Plant: `realistic` (stall %d mA, %.2f N·m measured on it at 7.4 V with its bus). "
            "Multi-turn closed loop: %u h simulated. %u of %u checks meet their target.\n\n",
            s_stall_ma, s_stall_unm / 1e6, s_hours, prv_met(), s_nchecks);
    fprintf(f, "| # | criterion | check | target | measured | |\n|---|---|---|---|---|---|\n");
    for (unsigned i = 0; i < s_nchecks; i++) {
        const br_check_t *c = &s_checks[i];
        fprintf(f, "| %u ", c->criterion);
        prv_md_cell(f, k_criterion[c->criterion]);
        prv_md_cell(f, c->what);
        prv_md_cell(f, c->target);
        prv_md_cell(f, c->measured);
        fprintf(f, "| %s |\n", c->meets ? "meets" : "**misses**");
    }
    fprintf(f, "\nThe defects the issue lists, on the same plant:\n\n%s\n", s_defects);
    fprintf(f, "Over the bus:\n\n%s\n", s_bus_text);
    for (unsigned k = 1; k <= 8u; k++) {
        fprintf(f, "![%u. %s](control-quality/c%u.png)\n\n", k, k_criterion[k], k);
    }
    return fclose(f) == 0;
}

/* Host CPU time per 1 ms plant step, both configurations, driven with a
 * PWM square wave. */
static void prv_cost(void)
{
    static km_plant_t p;
    const km_plant_config_t *cfgs[2] = {&km_plant_ideal_config, &km_plant_realistic_config};
    for (unsigned k = 0; k < 2u; k++) {
        (void)km_plant_init(&p, cfgs[k]);
        const clock_t t0 = clock();
        for (int32_t i = 0; i < 1000000; i++) {
            const km_plant_input_t in = {KM_PLANT_DRIVE, (int16_t)((i / 100) % 2 != 0 ? 300 : -300), 0};
            km_plant_step(&p, &in, TICK_US);
        }
        const double us = (double)(clock() - t0) / CLOCKS_PER_SEC; /* s per 1e6 steps = µs per step */
        printf("%s: %.3f µs of host CPU per 1 ms step (sub-step %u µs)\n", k == 0u ? "ideal" : "realistic",
               us, p.sub_us);
    }
}

/* The criteria of a --only list ("4", "1,4"), as bits 1..8; 0 = all. */
static unsigned prv_criteria(const char *list)
{
    unsigned bits = 0;
    for (const char *c = list; *c != '\0'; c++) {
        if (*c >= '1' && *c <= '8') {
            bits |= 1u << (unsigned)(*c - '0');
        }
    }
    return bits;
}

/* Whether criterion `k` runs (all without --only). */
static bool prv_wanted(unsigned k)
{
    return s_only == 0u || (s_only & (1u << k)) != 0u;
}

/* The criteria in order (those of --only), then the bus figures (all only). */
static void prv_run_criteria(void)
{
    if (prv_wanted(1)) {
        prv_c1();
    }
    if (prv_wanted(2)) {
        prv_c2_steady();
        prv_c2_step();
    }
    if (prv_wanted(3)) {
        prv_c3_overshoot();
        prv_c3_retarget();
    }
    if (prv_wanted(4)) {
        prv_c4();
    }
    if (prv_wanted(5)) {
        prv_c5();
    }
    if (prv_wanted(6)) {
        prv_c6();
    }
    if (prv_wanted(7)) {
        prv_c7_loop();
        prv_c7_day();
        prv_c7_same_hold();
        prv_c7_wrap();
    }
    if (prv_wanted(8)) {
        prv_c8();
    }
    if (s_only == 0u) {
        prv_bus_supply();
    }
}

/* Runs every criterion in order; exit 1 only on a broken run. */
int main(int argc, char **argv)
{
    const char *dir = getenv("KM_BENCH_CONTROL_DIR");
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--cost") == 0) {
            prv_cost();
            return 0;
        }
        if (strcmp(argv[i], "--hours") == 0 && i + 1 < argc) {
            s_hours = (unsigned)strtoul(argv[++i], NULL, 10);
        } else if (strcmp(argv[i], "--only") == 0 && i + 1 < argc) {
            s_only = prv_criteria(argv[++i]);
        } else if (strcmp(argv[i], "--seed") == 0 && i + 1 < argc) {
            s_lcg = (uint32_t)strtoul(argv[++i], NULL, 10);
        } else {
            dir = argv[i];
        }
    }
    if (dir == NULL || dir[0] == '\0') {
        dir = ".";
    }
    char path[512];
    (void)snprintf(path, sizeof path, "%s/control_traces.csv", dir);
    s_csv = fopen(path, "w");
    if (s_csv == NULL || s_hours == 0u) {
        printf("BROKEN RUN: cannot write %s (or --hours 0)\n", path);
        return 1;
    }
    fprintf(
        s_csv,
        "criterion,series,t_ms,target_deg,shaft_deg,report_deg,speed_dps,pwm,current_ma,peak_ma,running\n");
    printf("Control quality (issue 20): the real control code and dispatcher on the realistic plant,\n"
           "1 kHz tick, virtual time. Reproduce: %s [--hours H] [--only LIST] [--seed S] [out-dir]  "
           "(tools/bench/bench-control)\n\n",
           argv[0]);
    prv_measure_stall();
    printf("plant: stall %d mA, %.2f N.m (full PWM, 7.4 V, its 4-servo bus)\n\n", s_stall_ma,
           s_stall_unm / 1e6);
    prv_csv_point(0, "stall", 0, s_stall_ma, s_stall_unm / 1e6);
    prv_run_criteria();
    prv_print();
    if (fclose(s_csv) != 0 || !prv_markdown(dir)) {
        printf("BROKEN RUN: cannot finish the outputs in %s\n", dir);
        return 1;
    }
    printf("\ntraces: %s; section: %s/control_quality.md\n", path, dir);
    return s_broken;
}
