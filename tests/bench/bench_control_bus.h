/* SPDX-License-Identifier: Apache-2.0 */
/* Part of tests/bench/bench_control.c (included once there): twelve servos
 * on one supply (issue 20 section 2, "a 12-servo bus on one supply reports
 * the worst sag during simultaneous moves").
 *
 * Twelve realistic plants (KM-SIM-P135 each, control through
 * tests/support/km_plant_rig.h: 1 kHz tick, one-tick PWM delay) share one
 * 2S pack: every plant's own source is its lead (supply_r_mohm) and the
 * bench closes the shared part itself: the bus node is the pack's 7.4 V
 * less BUS_R_MOHM times the sum of the twelve supply currents of the last
 * tick (the bulk capacitors average the 20 kHz pulses over far less than a
 * tick), set on every plant as its supply for the next tick. The plants'
 * own model of a shared bus (bus_servos) is set to one servo with no
 * shared resistance so the sag is not counted twice. All twelve get the
 * same move at the same tick (a sync write): 0x66 fastest +90 deg from
 * -45 deg, 0x65 +90 deg in 500 ms, and the fastest move again with each
 * servo lifting 0.5 N.m (an arm), product defaults (0x5C 2000 mA). Reported: the lowest bus voltage, the
 * peak total current, the slowest servo's end (bit 7) against one servo
 * alone on the same pack. */
#ifndef BENCH_CONTROL_BUS_H
#define BENCH_CONTROL_BUS_H

#include "../support/km_plant_rig.h"

#define BUS_N 12u
#define BUS_R_MOHM 100 /* the 2S pack and the shared harness (docs/plant.md bus_r_mohm) */
#define BUS_PACK_MV 7400

typedef struct {
    int32_t min_mv;      /* the lowest bus node voltage */
    int32_t peak_ma;     /* the largest total supply current */
    uint32_t slowest_ms; /* the last bit 7 to clear, from the command */
} bus_result_t;

static kr_rig_t s_bus_rig[BUS_N];
static char s_bus_text[2048]; /* the bus figures, for the summary and the document */

/* Adds a line to the bus figures. */
static void prv_bus_line(const char *fmt, ...)
{
    const size_t used = strlen(s_bus_text);
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(s_bus_text + used, sizeof s_bus_text - used, fmt, ap);
    va_end(ap);
}

static km_plant_config_t s_bus_cfg;
static km_plant_real_t s_bus_real;

/* The plants' configuration: realistic, the shared source left to the bench. */
static void prv_bus_config(void)
{
    s_bus_cfg = km_plant_realistic_config;
    s_bus_real = km_plant_realistic_params;
    s_bus_real.bus_servos = 1u;
    s_bus_real.bus_r_mohm = 0u;
    s_bus_cfg.real = &s_bus_real;
}

/* `n` servos on the pack, each holding -45 deg against `load_unm`; the
 * move of kind `kind` (+90 deg, `param`) sent to all at once. */
static bool prv_bus_run(unsigned n, km_move_kind_t kind, uint16_t param, int32_t load_unm, bus_result_t *out)
{
    out->min_mv = BUS_PACK_MV;
    out->peak_ma = 0;
    out->slowest_ms = 0;
    for (unsigned k = 0; k < n; k++) {
        kr_init_at(&s_bus_rig[k], &s_bus_cfg, -450);
        s_bus_rig[k].in.ext_torque_unm = -load_unm; /* against the move */
        if (!kr_torque(&s_bus_rig[k], 2)) {
            return false;
        }
    }
    uint32_t running = 0u;
    for (uint32_t t = 0; t < 4000u; t++) {
        if (t == 1000u) {
            for (unsigned k = 0; k < n; k++) {
                if (!kr_move(&s_bus_rig[k], kind, 450, param)) {
                    return false;
                }
            }
            running = (1u << n) - 1u;
        }
        int32_t total_ma = 0;
        for (unsigned k = 0; k < n; k++) {
            total_ma += km_plant_supply_ma(&s_bus_rig[k].plant);
        }
        const int32_t node_mv = BUS_PACK_MV - total_ma * BUS_R_MOHM / 1000;
        for (unsigned k = 0; k < n; k++) {
            km_plant_set_supply_mv(&s_bus_rig[k].plant, node_mv);
            kr_tick(&s_bus_rig[k]);
            if (t > 1001u && (running & (1u << k)) != 0u && !s_bus_rig[k].live.running) {
                running &= ~(1u << k);
                out->slowest_ms = t - 1000u;
            }
        }
        if (t >= 1000u) {
            out->min_mv = node_mv < out->min_mv ? node_mv : out->min_mv;
            out->peak_ma = total_ma > out->peak_ma ? total_ma : out->peak_ma;
        }
    }
    return running == 0u;
}

/* The bus section: the worst sag of twelve servos moving together. */
static void prv_bus_supply(void)
{
    prv_bus_config();
    static const struct {
        km_move_kind_t kind;
        uint16_t param;
        int32_t load_unm;
        const char *what;
    } cases[] = {
        {KM_MOVE_SPEED, 0u, 0, "0x66 fastest +90°, no load"},
        {KM_MOVE_TIME, 500u, 0, "0x65 +90° in 500 ms, no load"},
        {KM_MOVE_SPEED, 0u, 500000, "0x66 fastest +90° against 0.5 N·m each"},
    };
    prv_bus_line(
        "Twelve servos on one 2S pack (%d mΩ shared, `tests/bench/bench_control_bus.h`), the same move "
        "sent to all at once, against one servo alone on the same pack:\n\n",
        BUS_R_MOHM);
    for (unsigned i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        bus_result_t one, all;
        if (!prv_bus_run(1u, cases[i].kind, cases[i].param, cases[i].load_unm, &one) ||
            !prv_bus_run(BUS_N, cases[i].kind, cases[i].param, cases[i].load_unm, &all)) {
            printf("BROKEN RUN: bus supply case %u\n", i);
            s_broken = 1;
            return;
        }
        prv_bus_line("- bus: %s: 12 servos: bus at %.2f V at worst (sag %.2f V), %.2f A peak; slowest end "
                     "%u ms (one servo alone: %.2f V, %.2f A, %u ms)\n",
                     cases[i].what, all.min_mv / 1000.0, (BUS_PACK_MV - all.min_mv) / 1000.0,
                     all.peak_ma / 1000.0, (unsigned)all.slowest_ms, one.min_mv / 1000.0,
                     one.peak_ma / 1000.0, (unsigned)one.slowest_ms);
    }
}

#endif
