/* SPDX-License-Identifier: Apache-2.0 */
/* Protection scenarios on the plant (issue 9 "Tests must show"): docs/protocol.md
 * §5.2 (0x32 enable, 0x33 release mode, 0x34 action, 0x35 self-test, 0x36
 * flags and clear, 0x3C-0x3F thresholds) and §4 status bits 0-4, run through
 * the whole control tick (km_control_step via the plant rig), not the
 * supervisor alone (tests/unit/control/test_protect.c does that).
 *
 * The table below is data: each row names its inputs (a stimulus over time on
 * the plant: supply, winding temperature, external load torque, plant faults;
 * an obstacle on the shaft's way; and a command: torque off, holding, a
 * 0x66 move, motor mode 0x6E), its settings, the expected trip window, the
 * action, the flags and the release. One runner plays every row and prints
 * one line per row (name, trip time seen, 0x36 bits seen, action, release
 * seen, 0x64 after, and d where the trip bound is checked).
 *
 * Time base: t = 0 is the first control tick that samples the stimulus (the
 * stimulus is put on the plant before that tick). "trip ms" is the number of
 * ticks from t = 0 to the tick whose live registers first show the
 * protection, inclusive: km_protect.h's bound "a sustained excursion trips
 * within [T, T + 1 tick] of its first sample when the timer read 0" reads
 * here as trip ms in [d + T, d + T + 1], d the stimulus-to-excursion delay.
 * Supply and temperature are read in the tick they are set (d = 0, so the
 * window is [T, T + 1] exactly); a load torque or a motor command acts
 * through the loop and the motor (d measured and stated in the row). The
 * release is counted the same way from the first tick without the stimulus
 * (automatic release: the timer counts back from T, so [T, T + 1] again) or,
 * where the protection's own action ends the cause (motor mode into an end
 * stop), from the trip.
 *
 * Checked in every row, besides its own expectations (on every tick where
 * it is a state):
 *   - every active protection is reported (0x36, status bits 0-3) and 0x64
 *     reads 5 while protecting (§5.2, km_control.h);
 *   - the bridge does what 0x34 says for the highest active protection
 *     (§5.2 priority voltage > temperature > current > stall), an oracle
 *     written from the spec table, not from km_protect.c: free, brake, or
 *     hold = PWM with the shaft near where it tripped (servo mode, current
 *     and stall only; 1x is brake elsewhere); so releasing a lower one never
 *     re-enables the output while a higher one is active;
 *   - 20 ms after a trip a move, a torque-on and a motor request are refused
 *     (§6 outcome: status bit 6) and nothing is driven by them;
 *   - after the release 0x64 returns to what the row says (km_control.h: 0/1
 *     if it was off, 2 after a hold, else 3 = armed) and, unless holding,
 *     the bridge is never driven again (a released servo never moves by
 *     itself), a move stopped by a trip never resumes, and the next
 *     rotation command is taken and moves the shaft.
 *
 * Self-test rows (§5.2 0x35, §4 bit 4): the fault is found after the
 * power-on samples (KM_SELFTEST_SAMPLES ticks), after 500 ms driven
 * without current, or by the run-time sensor checks (a wiper lost: 20 ms;
 * an NTC lost: 500 ms); every motion request is refused, 0x64 = 0 is still
 * taken, the output is free; a restart (control started afresh on the
 * plant, the fault mended) moves again.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "km_plant_rig.h"

#define NO_TRIP (-1)
#define NM(x) ((int32_t)((x)*1000000.0)) /* N.m to the plant's uN.m */

typedef enum { CMD_OFF, CMD_HOLD, CMD_MOTOR } cmd_t;

typedef enum { ST_NONE, ST_SUPPLY, ST_TEMP, ST_TORQUE, ST_FAULT, ST_WALL } stim_kind_t;

/* A stimulus on one plant input, t in ms from t = 0 (the row's start):
 *   before `at`: base;
 *   [at, at + dur): level, or a ramp from base to level when `ramp`, or
 *     pulses (level for `on` of every `period` ms, base the rest) when
 *     `period` != 0;
 *   [at + dur, at + dur + dur2): level2 (when dur2 != 0);
 *   after: base.
 * Plus, on every tick, deterministic LCG noise in [-noise, +noise].
 * ST_WALL is an obstacle on the shaft's way during [at, at + dur): a spring
 * of `level` uN.m per 0.1 deg pushing back past `base` (0.1 deg, positive
 * side), none elsewhere. */
typedef struct {
    stim_kind_t kind;
    int32_t base;
    int32_t level;
    uint32_t at;
    uint32_t dur;
    bool ramp;
    uint32_t period;
    uint32_t on;
    int32_t level2;
    uint32_t dur2;
    int32_t noise;
} stim_t;

typedef struct {
    uint32_t at;    /* ms from t = 0 */
    uint8_t mask;   /* 0x36 bits written */
    bool expect_ok; /* accepted, or refused with status bit 6 */
} clear_t;

typedef enum { REL_NONE, REL_AUTO, REL_CMD, REL_DISABLE } rel_t;

typedef enum { ACT_NONE, ACT_FREE, ACT_BRAKE, ACT_HOLD } act_t;

typedef struct {
    const char *name;
    /* command before t = 0 */
    cmd_t cmd;
    int16_t motor_pwm;   /* CMD_MOTOR: 0x6E PWM */
    int16_t move_target; /* CMD_HOLD: a 0x66 move at t = 0 to this (0.1 deg), 0 = none */
    uint16_t move_speed; /* its deg/s */
    uint32_t pre_ms;     /* settling between the command and t = 0 */
    int32_t start_ddeg;  /* shaft at boot, sensor frame */
    /* settings (§5.2) */
    uint8_t enable;         /* 0x32 */
    uint8_t release;        /* 0x33 */
    uint8_t state;          /* 0x34 */
    uint8_t v_high, v_low;  /* 0x3C */
    uint8_t t_trip, t_hyst; /* 0x3D */
    uint16_t i_trip;
    uint8_t i_time; /* 0x3E */
    uint16_t s_pwm;
    uint8_t s_time; /* 0x3F */
    /* stimulus */
    stim_t stim[2];
    uint32_t run_ms;
    clear_t clear[2];
    uint32_t ts_at; /* a 0x64 write while protecting at this ms (0 = none): taken */
    uint8_t ts_val; /* its value, 0 or 1 */
    uint32_t en_at; /* a 0x32 write at this ms (0 = none) */
    uint8_t en_val; /* its value */
    /* expectations */
    int32_t trip_lo, trip_hi; /* ms, or NO_TRIP */
    uint8_t bits;             /* 0x36 bits seen over the run */
    act_t act;                /* bridge 50 ms after the trip */
    rel_t rel;
    bool rel_from_trip;     /* release counted from the trip (the action ends the cause) */
    int32_t rel_lo, rel_hi; /* ms after the stimulus ends (or the trip) */
    uint8_t ts_after;       /* 0x64 after the release */
    bool chatter;           /* the loop's current crosses the threshold more than once: no [T, T + 1] bound */
    bool partial;           /* a lower protection released while a higher stays */
    int16_t hold_tol;       /* 0.1 deg a hold may move from the trip position; 0 = HOLD_TOL_DDEG */
    /* self-test rows */
    uint32_t boot_fault;    /* plant fault from power-on */
    int32_t boot_supply_mv; /* 0 = the plant's default */
    uint8_t hw;             /* 0x35 bits expected (latched) */
} row_t;

/* Product defaults (boards/sim-common/km_sim_product.c, §5.2 table):
 * 0x32 = 0x0F, 0x33 = 0, 0x34 = 0x54 (voltage free, the rest brake),
 * 0x3C = 9 V / 6 V, 0x3D = 60 / 5, 0x3E = 1500 mA / 2 s, 0x3F = 600 / 2 s. */
#define DEFAULTS SET(0x0F, 0x00, 0x54, 1500, 20, 600, 20)
/* The same with named changes. */
#define SET(en, rel, st, it, itime, sp, stime)                                                           \
    .enable = (en), .release = (rel), .state = (st), .v_high = 9, .v_low = 6, .t_trip = 60, .t_hyst = 5, \
    .i_trip = (it), .i_time = (itime), .s_pwm = (sp), .s_time = (stime)

/* 0x34 fields: [7:6] stall, [5:4] temperature, [3:2] current, [1:0] voltage */
#define A34(stall, temp, cur, volt) (uint8_t)(((stall) << 6) | ((temp) << 4) | ((cur) << 2) | (volt))

#define SUPPLY_MV 7400
#define T_BASE 400   /* 40.0 degC */
#define LOAD NM(1.5) /* holding it takes ~1.9 A and ~PWM 750 on this plant */

/* Shorthands for the stimuli. */
#define SAG(mv, at, dur)                                              \
    {                                                                 \
        ST_SUPPLY, SUPPLY_MV, (mv), (at), (dur), false, 0, 0, 0, 0, 0 \
    }
#define HEAT(dc, at, dur)                                        \
    {                                                            \
        ST_TEMP, T_BASE, (dc), (at), (dur), false, 0, 0, 0, 0, 0 \
    }
#define HEAT2(dc, at, dur, dc2, dur2, base)                               \
    {                                                                     \
        ST_TEMP, (base), (dc), (at), (dur), false, 0, 0, (dc2), (dur2), 0 \
    }
#define PUSH(unm, at, dur)                                     \
    {                                                          \
        ST_TORQUE, 0, (unm), (at), (dur), false, 0, 0, 0, 0, 0 \
    }
#define PULSES(kind, base, lvl, dur, period, on)                      \
    {                                                                 \
        kind, (base), (lvl), 0, (dur), false, (period), (on), 0, 0, 0 \
    }
#define NONE                                      \
    {                                             \
        ST_NONE, 0, 0, 0, 0, false, 0, 0, 0, 0, 0 \
    }
#define NOCLEAR         \
    {                   \
        {0, 0, false},  \
        {               \
            0, 0, false \
        }               \
    }

/* ----------------------------------------------------------------------
 * The table. Windows: see the time base at the top. Where a row says
 * "d = ..." the delay was measured on the plant and is explained there. */
/* clang-format off: one scenario per row, columns aligned by hand */
static const row_t k_rows[] = {
    /* ---- temperature (§5.2 0x3D: trip at 60, release below 55, 3 s) ---- */
    {.name = "temp_slow_ramp_with_noise_trips_brake_auto_release",
     /* 50.0 -> 65.0 degC over 30 s (0.5 degC/s) with +-1.5 degC LCG noise,
      * 65 for 2 s, then 50. Noise can reach 60 from ramp 58.5 (t = 17 s)
      * and the ramp alone is over from 61.5 (t = 23 s): the up/down timer
      * trips no earlier than 17 + 3 s and no later than 23 + 3 s. After
      * the drop (50 +- 1.5 < 55) the timer counts back from 3 s. */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {{ST_TEMP, 500, 650, 0, 30000, true, 0, 0, 650, 2000, 15}, NONE},
     .run_ms = 36000,
     .clear = NOCLEAR,
     .trip_lo = 20000,
     .trip_hi = 26001,
     .bits = KM_PROT_TEMPERATURE,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "temp_one_sample_spike_no_trip",
     /* 120.0 degC for one sample: one tick on the timer, gone the next */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {HEAT(1200, 100, 1), NONE},
     .run_ms = 4000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},
    {.name = "temp_spikes_every_10ms_no_trip",
     /* 100.0 degC one sample in ten for 10 s: duty 10 % never trips */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {PULSES(ST_TEMP, T_BASE, 1000, 10000, 10, 1), NONE},
     .run_ms = 11000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},
    {.name = "temp_step_trips_at_3s_brake_releases_3s_after",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {HEAT(700, 0, 5000), NONE},
     .run_ms = 9000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_TEMPERATURE,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "temp_in_hysteresis_band_stays_tripped_until_below_55",
     /* 70 for 4 s, 57 (>= 60 - 5: the excursion holds) for 5 s, then 40:
      * the release is counted from the end of the band */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {HEAT2(700, 0, 4000, 570, 5000, T_BASE), NONE},
     .run_ms = 13000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_TEMPERATURE,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "temp_chatter_at_release_threshold_releases_once",
     /* 70 degC for 4 s (trips at 3000), then 55.0 / 54.9 degC, at 55.0
      * (still the excursion: >= 60 - 5) 4 ms of every 10 for 30 s: the
      * timer, clamped at 3 s, reads 2994 ms after the first period and
      * loses 2 ms net a period after that: after 1497 periods it reads
      * 2 ms, the 1498th takes it to 6 and down to 0 on its 10th tick:
      * released at tick 4000 + 14970 + 10 = 18980, 15980 ms after the
      * trip (about T / (1 - 2 x 0.4) = 15 s into the chatter), once: 55
      * is below the 60 trip once released, so it never trips again */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {HEAT(700, 0, 4000), {ST_TEMP, 549, 550, 4000, 30000, false, 10, 4, 0, 0, 0}},
     .run_ms = 34000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_TEMPERATURE,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_from_trip = true,
     .rel_lo = 15980,
     .rel_hi = 15981,
     .ts_after = 3},
    {.name = "temp_chatter_at_trip_duty_40pct_no_trip",
     /* 60.0 / 59.9 degC, over 4 ms of every 10 for 20 s: < 50 % never trips */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {PULSES(ST_TEMP, 599, 600, 20000, 10, 4), NONE},
     .run_ms = 20000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},
    {.name = "temp_chatter_at_trip_duty_60pct_trips_late",
     /* 6 up, 4 down per 10 ms: net +2 ms per period; after 1497 periods
      * the timer is at 2994 ms and reaches 3000 on the 6th tick of the next
      * one: trip at 14976 ms exactly (about T / (2 x 0.6 - 1) = 15 s).
      * Not released: 59.9 degC is inside the hysteresis band */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {PULSES(ST_TEMP, 599, 600, 20000, 10, 6), NONE},
     .run_ms = 20000,
     .clear = NOCLEAR,
     .trip_lo = 14976,
     .trip_hi = 14977,
     .bits = KM_PROT_TEMPERATURE,
     .act = ACT_BRAKE,
     .rel = REL_NONE},
    {.name = "temp_release_by_command_refused_in_band_accepted_below",
     /* 0x33 bit 2: 70 for 4 s, 57 for 3 s (the excursion holds: refused),
      * then 40 (accepted at 8000 = 1000 ms after the band ends + the tick) */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0F, 0x04, 0x54, 1500, 20, 600, 20),
     .stim = {HEAT2(700, 0, 4000, 570, 3000, T_BASE), NONE},
     .run_ms = 12000,
     .clear = {{5000, KM_PROT_TEMPERATURE, false}, {8000, KM_PROT_TEMPERATURE, true}},
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_TEMPERATURE,
     .act = ACT_BRAKE,
     .rel = REL_CMD,
     .rel_lo = 1001,
     .rel_hi = 1001,
     .ts_after = 3},
    {.name = "temp_disabled_never_trips",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0B, 0x00, 0x54, 1500, 20, 600, 20),
     .stim = {HEAT(900, 0, 8000), NONE},
     .run_ms = 9000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},
    {.name = "temp_action_free_servo_mode",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0F, 0x00, A34(1, 0, 1, 0), 1500, 20, 600, 20),
     .stim = {HEAT(700, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_TEMPERATURE,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "temp_action_hold_acts_as_brake_servo_mode",
     /* §5.2 0x34: temperature allows only 00/01; 1x is brake */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0F, 0x00, A34(1, 2, 1, 0), 1500, 20, 600, 20),
     .stim = {HEAT(700, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_TEMPERATURE,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "temp_action_brake_motor_mode",
     /* 0x6E PWM 300 pushing on the end stop (0.75 A, below current and
      * stall thresholds); the motor is stopped and does not restart */
     .cmd = CMD_MOTOR,
     .motor_pwm = 300,
     .pre_ms = 2000,
     DEFAULTS,
     .stim = {HEAT(700, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_TEMPERATURE,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "temp_action_free_motor_mode",
     .cmd = CMD_MOTOR,
     .motor_pwm = 300,
     .pre_ms = 2000,
     SET(0x0F, 0x00, A34(1, 0, 1, 0), 1500, 20, 600, 20),
     .stim = {HEAT(700, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_TEMPERATURE,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "temp_torque_off_trips_returns_to_off",
     /* 0x64 = 0 when it tripped: 0x64 returns to 0 (km_control.h) */
     .cmd = CMD_OFF,
     .pre_ms = 100,
     DEFAULTS,
     .stim = {HEAT(700, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_TEMPERATURE,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 0},

    /* ---- voltage (§5.2 0x3C 9 V / 6 V, 3 s; 0x34 default free) ---- */
    {.name = "voltage_sag_2900ms_no_trip",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {SAG(5000, 0, 2900), NONE},
     .run_ms = 5000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},
    {.name = "voltage_sag_3500ms_trips_free_auto_release",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {SAG(5000, 0, 3500), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "voltage_two_1900ms_sags_1100ms_apart_no_trip",
     /* 1.9 s low, 1.1 s back, 1.9 s low: the up/down timer reads 1.9 s,
      * 0.8 s when the second sag begins, 2.7 s at its end: < 3 s */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {PULSES(ST_SUPPLY, SUPPLY_MV, 5000, 4900, 3000, 1900), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},
    {.name = "voltage_high_9v6_trips_free",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {SAG(9600, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "voltage_brownout_ramp_trips_3s_after_6v",
     /* 7.4 -> 4.0 V over 10 s (0.34 V/s), 4 V for 2 s, then 7.4 V. The
      * ramp (7400 - 3400 t / 10000 mV, integer) first reads below 6000 mV
      * at t = 4121 (4120 gives 7400 - 1400 = 6000 exactly: not below);
      * the holding servo draws a few mA (x 0.15 ohm: < 1 mV at the
      * terminals), so d = 4121: trip at 4121 + 3000 (+1) */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {{ST_SUPPLY, SUPPLY_MV, 4000, 0, 10000, true, 0, 0, 4000, 2000, 0}, NONE},
     .run_ms = 16000,
     .clear = NOCLEAR,
     .trip_lo = 7121,
     .trip_hi = 7122,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "voltage_one_sample_spike_20v_no_trip",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {SAG(20000, 100, 1), NONE},
     .run_ms = 4000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},
    {.name = "voltage_chatter_at_6v_duty_50pct_no_trip",
     /* 5.99 / 6.01 V every other tick for 20 s: presence never outweighs
      * absence by 3 s */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {PULSES(ST_SUPPLY, 6010, 5990, 20000, 2, 1), NONE},
     .run_ms = 20000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},
    {.name = "voltage_release_by_command_refused_while_low",
     /* 0x33 bit 0: clear at 4000 (still 5 V) refused; no automatic release
      * 3 s after; clear at 9000 accepted (9000 - 5000 + 1) */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0F, 0x01, 0x54, 1500, 20, 600, 20),
     .stim = {SAG(5000, 0, 5000), NONE},
     .run_ms = 11000,
     .clear = {{4000, KM_PROT_VOLTAGE, false}, {9000, KM_PROT_VOLTAGE, true}},
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_FREE,
     .rel = REL_CMD,
     .rel_lo = 4001,
     .rel_hi = 4001,
     .ts_after = 3},
    {.name = "voltage_auto_mode_clear_while_low_refused_after_accepted",
     /* 0x33 = 0 also releases by command (§5.2): refused at 3500 (5 V),
      * accepted at 4500, before the automatic release would come */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {SAG(5000, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = {{3500, KM_PROT_VOLTAGE, false}, {4500, KM_PROT_VOLTAGE, true}},
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_FREE,
     .rel = REL_CMD,
     .rel_lo = 501,
     .rel_hi = 501,
     .ts_after = 3},
    {.name = "voltage_torque_off_written_while_protecting_returns_to_0",
     /* 0x64 = 0 at 3500 (protecting): taken, and what 0x64 returns to */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {SAG(5000, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .ts_at = 3500,
     .ts_val = 0,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 0},
    {.name = "voltage_brake_off_written_while_protecting_returns_to_1",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {SAG(5000, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .ts_at = 3500,
     .ts_val = 1,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 1},
    {.name = "voltage_action_brake_servo_mode",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0F, 0x00, A34(1, 1, 1, 1), 1500, 20, 600, 20),
     .stim = {SAG(5000, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "voltage_action_hold_acts_as_brake_servo_mode",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0F, 0x00, A34(1, 1, 1, 2), 1500, 20, 600, 20),
     .stim = {SAG(5000, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "voltage_action_free_motor_mode",
     .cmd = CMD_MOTOR,
     .motor_pwm = 300,
     .pre_ms = 2000,
     DEFAULTS,
     .stim = {SAG(5000, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "voltage_action_brake_motor_mode",
     .cmd = CMD_MOTOR,
     .motor_pwm = 300,
     .pre_ms = 2000,
     SET(0x0F, 0x00, A34(1, 1, 1, 1), 1500, 20, 600, 20),
     .stim = {SAG(5000, 0, 4000), NONE},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "voltage_disabled_while_tripped_releases_at_once",
     /* 0x32 = 0x0E written at 4000 with the supply still at 5 V: released
      * on that tick (km_protect.h), 1001 ms after the trip, not watched
      * any more (the sag goes on to 5000: no new trip) */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {SAG(5000, 0, 5000), NONE},
     .run_ms = 7000,
     .clear = NOCLEAR,
     .en_at = 4000,
     .en_val = 0x0E,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_VOLTAGE,
     .act = ACT_FREE,
     .rel = REL_DISABLE,
     .rel_from_trip = true,
     .rel_lo = 1001,
     .rel_hi = 1001,
     .ts_after = 3},
    {.name = "voltage_disabled_never_trips",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0E, 0x00, 0x54, 1500, 20, 600, 20),
     .stim = {SAG(5000, 0, 8000), NONE},
     .run_ms = 9000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},

    /* ---- current (§5.2 0x3E): a load on the holding shaft; stall off ---- */
    {.name = "current_load_pulses_480ms_below_500ms_no_trip",
     /* 1.5 N.m for 480 ms of every 1500 ms, 0x3E time 5 (500 ms): over
      * 1.5 A for 480 - d = 464 ms each time (d = 16 ms, below) */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x07, 0x00, 0x54, 1500, 5, 600, 20),
     .stim = {PULSES(ST_TORQUE, 0, LOAD, 4500, 1500, 480), NONE},
     .run_ms = 5000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},
    {.name = "current_load_700ms_above_500ms_trips_brake",
     /* The loop's rise to 1.5 A against the load: with the settled hold's
      * dead band and its push integrator (docs/tuning.md) the current
      * touches 1.5 A at ~21 ms, dips under it and stays over from 27 ms:
      * the timer runs from the first touch (km_protect.h counts a dip
      * that short on), so no [T, T + 1] bound from d (chatter). The first
      * touch overshoots 0x5C (2 A here) to ~2.4 A for ~6 ms; the hold's
      * integrator does not grow while the current limiter holds the
      * output back (docs/tuning.md "Current limit"), so the dip after it
      * is one tick longer than when the integrator took ~16 PWM from that
      * overshoot: the up/down timer trips 2 ticks later (523, was 521),
      * in every row with this rise.
      * Braked, the load back-drives the shorted motor: the current stays
      * over 1.5 A until the load goes (a brake is a load on the motor
      * too); then it decays within 5 ms and the timer counts 500 ms */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x07, 0x00, 0x54, 1500, 5, 600, 20),
     .stim = {PUSH(LOAD, 0, 700), NONE},
     .run_ms = 3000,
     .clear = NOCLEAR,
     .trip_lo = 522,
     .trip_hi = 524,
     .chatter = true,
     .bits = KM_PROT_CURRENT,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_lo = 500,
     .rel_hi = 510,
     .ts_after = 3},
    {.name = "current_default_2s_trips_free",
     /* the same rise as above (touching 1.5 A at ~21 ms), T = 2 s (0x3E default); free: the current stops
      * at once and the release comes 2 s after the trip, the load still
      * turning the free shaft */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x07, 0x00, A34(1, 1, 0, 0), 1500, 20, 600, 20),
     .stim = {PUSH(LOAD, 0, 3000), NONE},
     .run_ms = 6000,
     .clear = NOCLEAR,
     .trip_lo = 2022,
     .trip_hi = 2024,
     .chatter = true,
     .bits = KM_PROT_CURRENT,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_lo = 2000,
     .rel_hi = 2001,
     .rel_from_trip = true,
     .ts_after = 3},
    {.name = "current_action_hold_servo_holds_near_trip_position",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x07, 0x00, A34(1, 1, 2, 0), 1500, 5, 600, 20),
     .stim = {PUSH(LOAD, 0, 2000), NONE},
     .run_ms = 4000,
     .clear = NOCLEAR,
     .trip_lo = 522, /* the rise of the row above, touching 1.5 A at ~21 ms */
     .trip_hi = 524,
     .chatter = true,
     .bits = KM_PROT_CURRENT,
     .act = ACT_HOLD,
     .rel = REL_AUTO,
     .rel_lo = 500,
     .rel_hi = 510,
     .ts_after = 2},
    {.name = "current_hold_release_by_command_refused_while_loaded",
     /* 0x33 bit 1: holding the load keeps the current over: refused at
      * 1500; load off at 2000; accepted at 2500 */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x07, 0x02, A34(1, 1, 2, 0), 1500, 5, 600, 20),
     .stim = {PUSH(LOAD, 0, 2000), NONE},
     .run_ms = 4000,
     .clear = {{1500, KM_PROT_CURRENT, false}, {2500, KM_PROT_CURRENT, true}},
     .trip_lo = 522, /* the rise of the row above, touching 1.5 A at ~21 ms */
     .trip_hi = 524,
     .chatter = true,
     .bits = KM_PROT_CURRENT,
     .act = ACT_HOLD,
     .rel = REL_CMD,
     .rel_lo = 501,
     .rel_hi = 501,
     .ts_after = 2},
    {.name = "current_hold_torque_off_written_while_holding_lets_go",
     /* holding (0x34 current 1x), 0x64 = 0 written at 1000: taken, the
      * hold ends (free), and 0x64 returns to 0 after the release */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x07, 0x00, A34(1, 1, 2, 0), 1500, 5, 600, 20),
     .stim = {PUSH(LOAD, 0, 1500), NONE},
     .run_ms = 3000,
     .clear = NOCLEAR,
     .ts_at = 1000,
     .ts_val = 0,
     .trip_lo = 522, /* the rise of the row above, touching 1.5 A at ~21 ms */
     .trip_hi = 524,
     .chatter = true,
     .bits = KM_PROT_CURRENT,
     .act = ACT_HOLD,
     .rel = REL_AUTO,
     .rel_from_trip = true,
     .rel_lo = 977, /* from the trip: the current ends at 1000, +500: 1501 - trip */
     .rel_hi = 979,
     .ts_after = 0},
    {.name = "current_motor_mode_end_stop_hold_acts_as_brake",
     /* 0x6E PWM 1000 from 0 deg into the +150 deg stop: the current limit
      * (0x5C 2000 mA) holds ~2 A there; d = 441 ms, the run to the stop
      * (measured on the current sensor by the runner). In motor
      * mode 1x is brake; braked at the stop there is no current: released
      * 500 ms after the trip */
     .cmd = CMD_MOTOR,
     .motor_pwm = 1000,
     .pre_ms = 0,
     SET(0x07, 0x00, A34(1, 1, 2, 0), 1500, 5, 600, 20),
     .stim = {NONE, NONE},
     .run_ms = 3000,
     .clear = NOCLEAR,
     .trip_lo = 941,
     .trip_hi = 942,
     .bits = KM_PROT_CURRENT,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_from_trip = true,
     .rel_lo = 500,
     .rel_hi = 520,
     .ts_after = 3},
    {.name = "current_motor_mode_free",
     .cmd = CMD_MOTOR,
     .motor_pwm = 1000,
     .pre_ms = 0,
     SET(0x07, 0x00, A34(1, 1, 0, 0), 1500, 5, 600, 20),
     .stim = {NONE, NONE},
     .run_ms = 3000,
     .clear = NOCLEAR,
     .trip_lo = 941,
     .trip_hi = 942,
     .bits = KM_PROT_CURRENT,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_from_trip = true,
     .rel_lo = 500,
     .rel_hi = 520,
     .ts_after = 3},
    {.name = "current_disabled_never_trips",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x05, 0x00, 0x54, 1500, 5, 600, 20),
     .stim = {PUSH(LOAD, 0, 3000), NONE},
     .run_ms = 4000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},

    /* ---- stall (§5.2 0x3F): drive >= 600 with no motion; current off ---- */
    {.name = "stall_load_pulses_700ms_stalled_311ms_below_500ms_no_trip",
     /* each 700 ms load stalls the shaft for 700 - d = 311 ms < 500 ms */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0D, 0x00, 0x54, 1500, 20, 600, 5),
     .stim = {PULSES(ST_TORQUE, 0, LOAD, 4500, 1500, 700), NONE},
     .run_ms = 5000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},
    {.name = "stall_load_above_500ms_trips_brake",
     /* d = 798 ms: the loop's integral pulls the loaded shaft back (it
      * moves more than 0.1 deg, which restarts the timing) until it
      * settles, 798 ms after the load comes (the settled hold's push
      * integrator grows with the error and waits while the shaft
      * returns: docs/tuning.md); trip at d + 500 (+1). Holding this load
      * takes ~1.9 A, 95 % of 0x5C (2 A here): on the way back the current
      * goes over 0x5C again and again, and the integrator does not push
      * harder while the current limiter holds the output back
      * (docs/tuning.md "Current limit"; 882 ms with a push integrator
      * that did not grow with the error) */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0D, 0x00, 0x54, 1500, 20, 600, 5),
     .stim = {PUSH(LOAD, 0, 1500), NONE},
     .run_ms = 3000,
     .clear = NOCLEAR,
     .trip_lo = 1298,
     .trip_hi = 1299,
     .bits = KM_PROT_STALL,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_from_trip = true,
     .rel_lo = 500,
     .rel_hi = 501,
     .ts_after = 3},
    {.name = "stall_default_2s_trips_free",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0D, 0x00, A34(0, 1, 1, 0), 1500, 20, 600, 20),
     .stim = {PUSH(LOAD, 0, 3000), NONE},
     .run_ms = 6000,
     .clear = NOCLEAR,
     .trip_lo = 2798, /* d = 798 ms as above, T = 2 s */
     .trip_hi = 2799,
     .bits = KM_PROT_STALL,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_from_trip = true,
     .rel_lo = 2000,
     .rel_hi = 2001,
     .ts_after = 3},
    {.name = "stall_action_hold_servo_holds_near_trip_position",
     /* released 500 ms after the stall condition last held: the drive
      * is >= 600 for some ticks after the load goes (515 ms while the
      * hold's integrator was frozen both ways; 525 ms since it may shrink:
      * the shaft stops 2.4 deg past instead of running on, and the hold
      * pulls it back at >= 600 PWM 34-39 ms after the load went;
      * docs/tuning.md "A load let go") */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0D, 0x00, A34(2, 1, 1, 0), 1500, 20, 600, 5),
     .stim = {PUSH(LOAD, 0, 2000), NONE},
     .run_ms = 4000,
     .clear = NOCLEAR,
     .trip_lo = 1298,
     .trip_hi = 1299,
     .bits = KM_PROT_STALL,
     .act = ACT_HOLD,
     .rel = REL_AUTO,
     .rel_lo = 500,
     .rel_hi = 530,
     .ts_after = 2},
    {.name = "stall_hold_release_by_command_refused_while_stalled",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0D, 0x08, A34(2, 1, 1, 0), 1500, 20, 600, 5),
     .stim = {PUSH(LOAD, 0, 2000), NONE},
     .run_ms = 4000,
     .clear = {{1500, KM_PROT_STALL, false}, {2500, KM_PROT_STALL, true}},
     .trip_lo = 1298,
     .trip_hi = 1299,
     .bits = KM_PROT_STALL,
     .act = ACT_HOLD,
     .rel = REL_CMD,
     .rel_lo = 501,
     .rel_hi = 501,
     .ts_after = 2},
    {.name = "stall_motor_mode_end_stop_trips_brake",
     /* 0x6E PWM 800 into the stop; the pot reads the shaft up to the
      * +150.0 deg stop (its rails are beyond), so the stall is timed from
      * there: d = 540 ms, the run at PWM 800 until the shaft stops */
     .cmd = CMD_MOTOR,
     .motor_pwm = 800,
     .pre_ms = 0,
     SET(0x0D, 0x00, 0x54, 1500, 20, 600, 5),
     .stim = {NONE, NONE},
     .run_ms = 3000,
     .clear = NOCLEAR,
     .trip_lo = 1040,
     .trip_hi = 1041,
     .bits = KM_PROT_STALL,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_from_trip = true,
     .rel_lo = 500,
     .rel_hi = 501,
     .ts_after = 3},
    {.name = "stall_motor_mode_hold_acts_as_brake",
     .cmd = CMD_MOTOR,
     .motor_pwm = 800,
     .pre_ms = 0,
     SET(0x0D, 0x00, A34(2, 1, 1, 0), 1500, 20, 600, 5),
     .stim = {NONE, NONE},
     .run_ms = 3000,
     .clear = NOCLEAR,
     .trip_lo = 1040,
     .trip_hi = 1041,
     .bits = KM_PROT_STALL,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_from_trip = true,
     .rel_lo = 500,
     .rel_hi = 501,
     .ts_after = 3},
    {.name = "stall_motor_mode_free",
     .cmd = CMD_MOTOR,
     .motor_pwm = 800,
     .pre_ms = 0,
     SET(0x0D, 0x00, A34(0, 1, 1, 0), 1500, 20, 600, 5),
     .stim = {NONE, NONE},
     .run_ms = 3000,
     .clear = NOCLEAR,
     .trip_lo = 1040,
     .trip_hi = 1041,
     .bits = KM_PROT_STALL,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_from_trip = true,
     .rel_lo = 500,
     .rel_hi = 501,
     .ts_after = 3},
    {.name = "stall_move_into_obstacle_hold_stops_it_where_it_tripped",
     /* a 0x66 move to +60 deg at 60 deg/s meets an obstacle at +30 deg (a
      * spring of 0.5 N.m/deg) until 3 s: d = 660 ms, the 500 ms run to the
      * obstacle and the shaft settling 3.2 deg into it; hold (0x34 stall
      * 1x) stops the move where the shaft is. The move's push came from its tracking error; holding
      * where it tripped starts the loop afresh (no error, no integral), so
      * the obstacle pushes the shaft back 2.4 deg before the loop holds it
      * (hold_tol 3.0 deg; a bumpless hold would need the position loop to
      * start its integral from the PWM in force). Holding needs less than
      * PWM 600 there: not a stall, released 500 ms after the trip with the
      * obstacle still there, to 0x64 = 2; the move never resumes */
     .cmd = CMD_HOLD,
     .move_target = 600,
     .move_speed = 60,
     .pre_ms = 300,
     SET(0x0D, 0x00, A34(2, 1, 1, 0), 1500, 20, 600, 5),
     .stim = {{ST_WALL, 300, 50000, 0, 3000, false, 0, 0, 0, 0, 0}, NONE},
     .run_ms = 5000,
     .clear = NOCLEAR,
     .trip_lo = 1160,
     .trip_hi = 1161,
     .bits = KM_PROT_STALL,
     .act = ACT_HOLD,
     .hold_tol = 30,
     .rel = REL_AUTO,
     .rel_from_trip = true,
     .rel_lo = 500,
     .rel_hi = 501,
     .ts_after = 2},
    {.name = "stall_move_into_obstacle_brake_move_never_resumes",
     /* the same with brake: the obstacle pushes the braked shaft back out;
      * released 500 ms after the trip to 0x64 = 3 (armed): the move is
      * not resumed */
     .cmd = CMD_HOLD,
     .move_target = 600,
     .move_speed = 60,
     .pre_ms = 300,
     SET(0x0D, 0x00, 0x54, 1500, 20, 600, 5),
     .stim = {{ST_WALL, 300, 50000, 0, 3000, false, 0, 0, 0, 0, 0}, NONE},
     .run_ms = 5000,
     .clear = NOCLEAR,
     .trip_lo = 1160,
     .trip_hi = 1161,
     .bits = KM_PROT_STALL,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_from_trip = true,
     .rel_lo = 500,
     .rel_hi = 501,
     .ts_after = 3},
    {.name = "stall_disabled_never_trips",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x05, 0x00, 0x54, 1500, 20, 600, 5),
     .stim = {PUSH(LOAD, 0, 3000), NONE},
     .run_ms = 4000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},

    /* ---- two at once (§5.2 priority voltage > temperature > current > stall) ---- */
    {.name = "prio_voltage_free_over_temperature_brake",
     /* 70 degC from 0 for 8 s (brake) and 5 V from 500 for 4 s (free):
      * temperature trips at 3000 (brake), voltage at 3500 (free decides),
      * voltage releases at 7500 (brake again, never PWM), temperature at
      * 11000 */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0F, 0x00, A34(1, 1, 1, 0), 1500, 20, 600, 20),
     .stim = {HEAT(700, 0, 8000), SAG(5000, 500, 4000)},
     .run_ms = 13000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_TEMPERATURE | KM_PROT_VOLTAGE,
     .act = ACT_BRAKE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .partial = true,
     .ts_after = 3},
    {.name = "prio_same_instant_both_reported_voltage_decides",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x0F, 0x00, A34(1, 1, 1, 0), 1500, 20, 600, 20),
     .stim = {SAG(5000, 0, 4000), HEAT(700, 0, 4000)},
     .run_ms = 8000,
     .clear = NOCLEAR,
     .trip_lo = 3000,
     .trip_hi = 3001,
     .bits = KM_PROT_TEMPERATURE | KM_PROT_VOLTAGE,
     .act = ACT_FREE,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .ts_after = 3},
    {.name = "prio_current_hold_then_temperature_brake_lower_release_keeps_off",
     /* load from 0 for 1500 ms: current trips (hold, ~500 ms); 70 degC
      * from 200 for 6 s: temperature trips at 3200 (brake decides); the
      * load is gone, the current protection releases 500 ms later under
      * the higher one: still brake, never PWM; temperature releases 3 s
      * after 6200; 0x64 returns to 3 (the output was let go) */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x07, 0x00, A34(1, 1, 2, 0), 1500, 5, 600, 20),
     .stim = {PUSH(LOAD, 0, 3500), HEAT(700, 200, 6000)},
     .run_ms = 11000,
     .clear = NOCLEAR,
     .trip_lo = 500,
     .trip_hi = 600,
     .chatter = true, /* the load's current rise (the current rows above) */
     .bits = KM_PROT_CURRENT | KM_PROT_TEMPERATURE,
     .act = ACT_HOLD,
     .rel = REL_AUTO,
     .rel_lo = 3000,
     .rel_hi = 3001,
     .partial = true,
     .ts_after = 3},
    {.name = "all_disabled_nothing_trips",
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     SET(0x00, 0x00, 0x54, 1500, 5, 600, 5),
     .stim = {PUSH(LOAD, 0, 4000), SAG(5000, 0, 4000)},
     .run_ms = 5000,
     .clear = NOCLEAR,
     .trip_lo = NO_TRIP,
     .act = ACT_NONE},

    /* ---- power-on self-test (§5.2 0x35, §4 bit 4): blocks motion until restart ---- */
    {.name = "selftest_pot_open_blocks_motion",
     .cmd = CMD_OFF,
     .pre_ms = 0,
     DEFAULTS,
     .stim = {NONE, NONE},
     .run_ms = 500,
     .clear = NOCLEAR,
     .trip_lo = 0,
     .trip_hi = 0,
     .act = ACT_FREE,
     .boot_fault = KM_PLANT_FAULT_POT_OPEN,
     .hw = KM_HW_POSITION},
    {.name = "selftest_ntc_open_blocks_motion",
     .cmd = CMD_OFF,
     .pre_ms = 0,
     DEFAULTS,
     .stim = {NONE, NONE},
     .run_ms = 500,
     .clear = NOCLEAR,
     .trip_lo = 0,
     .trip_hi = 0,
     .act = ACT_FREE,
     .boot_fault = KM_PLANT_FAULT_TEMP_OPEN,
     .hw = KM_HW_TEMPERATURE},
    {.name = "selftest_supply_sense_1v5_blocks_motion",
     /* 1.5 V: below the 2.0 V plausibility floor (the MCU runs, so the
      * divider is broken); the run is shorter than the voltage
      * protection's 3 s: only the self-test acts */
     .cmd = CMD_OFF,
     .pre_ms = 0,
     DEFAULTS,
     .stim = {NONE, NONE},
     .run_ms = 500,
     .clear = NOCLEAR,
     .trip_lo = 0,
     .trip_hi = 0,
     .act = ACT_FREE,
     .boot_supply_mv = 1500,
     .hw = KM_HW_VOLTAGE},
    {.name = "selftest_motor_open_while_driven_blocks_motion",
     /* lead opened at 0 on a holding servo, a move at 0: driven with no
      * current from the move's first tick; found 500 ms later. d = 1: the
      * PWM commanded at tick 0 drives the plant during tick 1 (the rig's
      * one-tick PWM delay), and the check counts the PWM driven */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {{ST_FAULT, 0, KM_PLANT_FAULT_MOTOR_OPEN, 0, 100000, false, 0, 0, 0, 0, 0}, NONE},
     .run_ms = 1500,
     .clear = NOCLEAR,
     .trip_lo = 501,
     .trip_hi = 502,
     .act = ACT_FREE,
     .hw = KM_HW_MOTOR},
    {.name = "selftest_ntc_open_while_running_blocks_motion",
     /* issue 18 item 3: the NTC opens at 0 on a holding servo (a move at
      * 0): it reads -40.0 degC; found 500 ms later, as at boot after */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {{ST_FAULT, 0, KM_PLANT_FAULT_TEMP_OPEN, 0, 100000, false, 0, 0, 0, 0, 0}, NONE},
     .run_ms = 1500,
     .clear = NOCLEAR,
     .trip_lo = 500,
     .trip_hi = 500,
     .act = ACT_FREE,
     .hw = KM_HW_TEMPERATURE},
    {.name = "selftest_pot_open_while_running_blocks_motion",
     /* the wiper opens at 0 on a moving servo: it reads the +165.0 deg
      * rail; found 20 ms later, the output let go */
     .cmd = CMD_HOLD,
     .pre_ms = 300,
     DEFAULTS,
     .stim = {{ST_FAULT, 0, KM_PLANT_FAULT_POT_OPEN, 0, 100000, false, 0, 0, 0, 0, 0}, NONE},
     .run_ms = 1500,
     .clear = NOCLEAR,
     .trip_lo = 20,
     .trip_hi = 20,
     .act = ACT_FREE,
     .hw = KM_HW_POSITION},
};
/* clang-format on */

#define N_ROWS (sizeof k_rows / sizeof k_rows[0])

/* ---------------------------------------------------------------------- */

static uint32_t s_lcg;

static int32_t prv_noise(int32_t n)
{
    s_lcg = s_lcg * 1103515245u + 12345u;
    if (n == 0) {
        return 0;
    }
    return (int32_t)((s_lcg >> 16) % (uint32_t)(2 * n + 1)) - n;
}

/* The stimulus value at t (ms). */
static int32_t prv_stim(const stim_t *s, uint32_t t)
{
    int32_t v = s->base;
    if (t >= s->at && t < s->at + s->dur) {
        const uint32_t u = t - s->at;
        if (s->ramp) {
            v = s->base + (int32_t)(((int64_t)(s->level - s->base) * (int64_t)u) / (int64_t)s->dur);
        } else if (s->period != 0u) {
            v = (u % s->period) < s->on ? s->level : s->base;
        } else {
            v = s->level;
        }
    } else if (s->dur2 != 0u && t >= s->at + s->dur && t < s->at + s->dur + s->dur2) {
        v = s->level2;
    }
    return v + prv_noise(s->noise);
}

#define PRE_T UINT32_MAX /* before t = 0: every stimulus at its base */

static bool prv_in_window(const stim_t *s, uint32_t t)
{
    return t != PRE_T && t >= s->at && t < s->at + s->dur + s->dur2;
}

/* First tick back at base after the stimulus. */
static uint32_t prv_stim_end(const stim_t *s)
{
    return s->at + s->dur + s->dur2;
}

static void prv_apply(kr_rig_t *r, const stim_t *s, uint32_t t)
{
    switch (s->kind) {
    case ST_SUPPLY:
        km_plant_set_supply_mv(&r->plant, prv_stim(s, t));
        break;
    case ST_TEMP:
        km_plant_set_temp_dc(&r->plant, prv_stim(s, t));
        break;
    case ST_TORQUE:
        r->in.ext_torque_unm = prv_stim(s, t);
        break;
    case ST_FAULT:
        km_plant_set_faults(&r->plant, (uint32_t)prv_stim(s, t));
        break;
    case ST_WALL: {
        const int32_t pos = km_plant_turns_ddeg(&r->plant);
        const bool there = t != PRE_T && t >= s->at && t < s->at + s->dur;
        r->in.ext_torque_unm = there && pos > s->base ? -(pos - s->base) * s->level : 0;
        break;
    }
    case ST_NONE:
    default:
        break;
    }
}

static void prv_settings(km_control_params_t *p, const row_t *w)
{
    p->prot_enable = w->enable;
    p->prot_release = w->release;
    p->prot_state = w->state;
    p->voltage_high_v = w->v_high;
    p->voltage_low_v = w->v_low;
    p->temp_trip_c = w->t_trip;
    p->temp_hysteresis_c = w->t_hyst;
    p->current_trip_ma = w->i_trip;
    p->current_time_100ms = w->i_time;
    p->stall_pwm = w->s_pwm;
    p->stall_time_100ms = w->s_time;
}

/* Power-on: the plant as the row leaves it at boot, control started with
 * the row's settings, one tick (kr_init_at with the settings in place
 * before km_control_init, as the app decodes the registers first). */
static void prv_boot(kr_rig_t *r, const row_t *w, bool with_faults)
{
    memset(r, 0, sizeof *r);
    assert_true(km_plant_init(&r->plant, &km_plant_default_config));
    km_plant_set_position_ddeg(&r->plant, w->start_ddeg);
    if (with_faults) {
        km_plant_set_faults(&r->plant, w->boot_fault);
        if (w->boot_supply_mv != 0) {
            km_plant_set_supply_mv(&r->plant, w->boot_supply_mv);
        }
    }
    kr_default_params(&r->params);
    prv_settings(&r->params, w);
    km_control_init(&r->ctl, &r->params);
    r->in.bridge = KM_PLANT_COAST;
    kr_tick(r);
}

/* The motor rows drive the shaft onto the +-150 deg stop: it stands in
 * for a jam inside the travel, so the product travel is lifted for them
 * (motor mode stops a pot product's run at its travel: km_motor_mode.h). */
static bool prv_motor(kr_rig_t *r, int16_t pwm)
{
    r->params.travel_min = INT16_MIN;
    r->params.travel_max = INT16_MAX;
    return kr_motor_signed(r, KM_RUN_PWM, pwm);
}

static bool prv_clear(kr_rig_t *r, uint8_t mask)
{
    km_request_t q;
    memset(&q, 0, sizeof q);
    q.kind = KM_REQ_PROTECTION_CLEAR;
    q.u.clear = mask;
    return kr_request(r, &q);
}

/* §5.2 0x34 read from the spec table: the action of the highest active
 * protection. Index of each protection's 2-bit field and priority order. */
static act_t prv_oracle(const row_t *w, uint8_t active, bool motor)
{
    static const uint8_t prio[4] = {KM_PROT_VOLTAGE, KM_PROT_TEMPERATURE, KM_PROT_CURRENT, KM_PROT_STALL};
    static const uint8_t shift[4] = {0, 4, 2, 6};
    for (unsigned k = 0; k < 4; k++) {
        if ((active & prio[k]) == 0u) {
            continue;
        }
        const unsigned a = (w->state >> shift[k]) & 3u;
        if (a == 0u) {
            return ACT_FREE;
        }
        if (a == 1u || motor || prio[k] == KM_PROT_VOLTAGE || prio[k] == KM_PROT_TEMPERATURE) {
            return ACT_BRAKE;
        }
        return ACT_HOLD;
    }
    return ACT_NONE;
}

static const char *prv_act_name(act_t a)
{
    return a == ACT_FREE ? "FREE" : a == ACT_BRAKE ? "BRAKE" : a == ACT_HOLD ? "HOLD" : "-";
}

static act_t prv_bridge_act(const kr_rig_t *r)
{
    return r->bridge.mode == KM_BRIDGE_FREE    ? ACT_FREE
           : r->bridge.mode == KM_BRIDGE_BRAKE ? ACT_BRAKE
                                               : ACT_HOLD;
}

/* "Held near the trip position": within 1.0 deg of where it tripped while
 * the load is on (once it is off the loop brings the shaft back to its
 * target, a few deg away under this load: holding, not a deviation). */
#define HOLD_TOL_DDEG 10

/* Motion while protecting or faulted: §6 outcome, refused. */
static void prv_motion_refused(kr_rig_t *r)
{
    const uint8_t ts = r->params.torque_switch;
    assert_false(kr_move(r, KM_MOVE_SPEED, (int16_t)(kr_pos(r) + 300), 100));
    assert_false(kr_move(r, KM_MOVE_TIME, (int16_t)(kr_pos(r) - 300), 500));
    assert_false(kr_torque(r, 2));
    assert_false(kr_torque(r, 3));
    assert_false(prv_motor(r, 500));
    assert_int_equal(r->params.torque_switch, ts);
}

/* A self-test row: the fault, motion refused, then a restart without it. */
static void prv_run_selftest(const row_t *w)
{
    kr_rig_t r;
    s_lcg = 1u;
    int32_t seen = NO_TRIP;
    uint32_t t0 = 0;
    prv_boot(&r, w, true);
    if (w->boot_fault == 0u && w->boot_supply_mv == 0) {
        /* run-time check: sound at boot, the stimulus from t = 0 */
        kr_run(&r, 50);
        assert_int_equal(r.live.hw_faults, 0);
        assert_true(kr_torque(&r, 2));
        kr_run(&r, w->pre_ms);
        for (uint32_t t = 0; t < w->run_ms; t++) {
            prv_apply(&r, &w->stim[0], t);
            if (t == 0u) {
                assert_true(kr_move(&r, KM_MOVE_SPEED, 900, 0));
            }
            kr_tick(&r);
            if (seen == NO_TRIP && r.live.hw_faults != 0u) {
                seen = (int32_t)t + 1;
                t0 = t;
            }
        }
    } else {
        /* power-on: counted from the boot tick; the check needs its
         * KM_SELFTEST_SAMPLES samples */
        for (uint32_t t = 1; t < w->run_ms; t++) {
            kr_tick(&r);
            if (seen == NO_TRIP && r.live.hw_faults != 0u) {
                seen = (int32_t)t + 1;
                t0 = t;
            }
        }
        assert_int_equal(seen, (int32_t)KM_SELFTEST_SAMPLES);
    }
    (void)t0;
    assert_int_equal(r.live.hw_faults & w->hw, w->hw);
    if (w->boot_fault == 0u && w->boot_supply_mv == 0) {
        assert_in_range(seen, w->trip_lo, w->trip_hi);
    }
    /* blocked: free output, 0x64 = 0, every motion refused */
    const int32_t pos = kr_pos(&r);
    prv_motion_refused(&r);
    assert_true(kr_torque(&r, 0)); /* writes still work: 0x64 = 0 is taken */
    kr_run(&r, 300);
    assert_int_equal(r.bridge.mode, KM_BRIDGE_FREE);
    assert_int_equal(r.live.torque_switch, 0);
    assert_int_equal(r.live.hw_faults & w->hw, w->hw);
    assert_true(kr_pos(&r) >= pos - 20 && kr_pos(&r) <= pos + 20); /* nothing moved it */

    /* restart with the fault mended: motion works again */
    kr_rig_t r2;
    prv_boot(&r2, w, false);
    kr_run(&r2, 50);
    assert_int_equal(r2.live.hw_faults, 0);
    assert_true(kr_move(&r2, KM_MOVE_SPEED, 300, 0));
    kr_run(&r2, 1000);
    assert_in_range(kr_pos(&r2), 280, 320);
    printf("  %-66s trip %6d ms  action %-5s  0x35=0x%02X  restart: moves to %d\n", w->name, seen,
           prv_act_name(prv_bridge_act(&r)), r.live.hw_faults, kr_pos(&r2));
}

/* The sensor shows an excursion of an enabled voltage, temperature or
 * current protection (§5.2 thresholds of the row), this tick. */
static bool prv_excursion_shows(const kr_rig_t *r, const row_t *w)
{
    km_sensors_t s;
    kr_sensors(r, &s); /* what control read this tick: the plant has not stepped since */
    const bool v = (w->enable & KM_PROT_VOLTAGE) != 0u &&
                   (s.voltage_mv > w->v_high * 1000 || s.voltage_mv < w->v_low * 1000);
    const bool t = (w->enable & KM_PROT_TEMPERATURE) != 0u && s.temperature_c10 >= w->t_trip * 10;
    const bool i =
        (w->enable & KM_PROT_CURRENT) != 0u && (s.current_ma > w->i_trip || s.current_ma < -w->i_trip);
    return v || t || i;
}

/* The protection that tripped first among `bits` (the rows start one at a
 * time, or two with the same T) */
static uint8_t prv_first_bit(uint8_t bits)
{
    return (bits & KM_PROT_VOLTAGE)       ? KM_PROT_VOLTAGE
           : (bits & KM_PROT_TEMPERATURE) ? KM_PROT_TEMPERATURE
           : (bits & KM_PROT_CURRENT)     ? KM_PROT_CURRENT
                                          : KM_PROT_STALL;
}

static void prv_run_row(const row_t *w)
{
    kr_rig_t r;
    s_lcg = 0x2545F491u ^ (uint32_t)strlen(w->name);
    prv_boot(&r, w, true);
    kr_run(&r, 50); /* the power-on self-test's samples */
    assert_int_equal(r.live.hw_faults, 0);
    if (w->cmd == CMD_HOLD) {
        assert_true(kr_torque(&r, 2));
    } else if (w->cmd == CMD_OFF) {
        assert_true(kr_torque(&r, 0));
    } else {
        assert_true(prv_motor(&r, w->motor_pwm));
    }
    /* the stimuli's base values from now on */
    for (uint32_t i = 0; i < w->pre_ms; i++) {
        for (unsigned k = 0; k < 2; k++) {
            if (w->stim[k].kind != ST_NONE) {
                prv_apply(&r, &w->stim[k], PRE_T);
            }
        }
        kr_tick(&r);
    }
    assert_int_equal(r.live.protections, 0);

    uint32_t t_end = 0;
    for (unsigned k = 0; k < 2; k++) {
        if (w->stim[k].kind != ST_NONE && prv_stim_end(&w->stim[k]) > t_end) {
            t_end = prv_stim_end(&w->stim[k]);
        }
    }
    const bool motor = w->cmd == CMD_MOTOR;
    int32_t trip = NO_TRIP;
    int32_t released = NO_TRIP;
    uint8_t seen_bits = 0;
    act_t act_seen = ACT_NONE;
    int32_t pos_trip = 0;
    int32_t hold_dev = 0;
    unsigned clears_done = 0;
    int32_t d = NO_TRIP; /* first tick a voltage, temperature or current excursion shows */
    bool partial = false;
    bool showed = false;
    int32_t d_run = NO_TRIP;
    uint8_t first_bits = 0; /* what tripped first */
    uint8_t prev_active = 0;

    for (uint32_t t = 0; t < w->run_ms; t++) {
        prv_apply(&r, &w->stim[0], t);
        if (w->stim[1].kind != w->stim[0].kind || prv_in_window(&w->stim[1], t)) {
            prv_apply(&r, &w->stim[1], t); /* on the same input: only within its window */
        }
        if (t == 0u && w->move_target != 0) {
            assert_true(kr_move(&r, KM_MOVE_SPEED, w->move_target, w->move_speed));
        }
        if (w->en_at != 0u && w->en_at == t) {
            r.params.prot_enable = w->en_val; /* as the dispatcher decodes a 0x32 write */
        }
        if (w->ts_at != 0u && w->ts_at == t) {
            assert_true(r.live.protecting);
            assert_true(kr_torque(&r, w->ts_val)); /* 0x64 = 0/1 taken while protecting (km_control.h) */
        }
        for (unsigned k = 0; k < 2; k++) {
            if (w->clear[k].mask != 0u && w->clear[k].at == t) {
                assert_int_equal(prv_clear(&r, w->clear[k].mask), w->clear[k].expect_ok);
                clears_done++;
            }
        }
        kr_tick(&r);
        const uint8_t active = r.live.protections;
        seen_bits |= active;
        /* d: where the excursion run that tripped began (a motor's
         * start-up current is an earlier, separate run) */
        const bool shows = prv_excursion_shows(&r, w);
        if (trip == NO_TRIP && shows && !showed) {
            d_run = (int32_t)t;
        }
        showed = shows;
        if ((prev_active & (uint8_t)~active) != 0u && active != 0u) {
            partial = true; /* a lower one released under a higher one (checked by the oracle above) */
        }
        prev_active = active;

        /* every active protection reported, 0x64 = 5 while protecting */
        assert_int_equal(r.live.protecting, active != 0u);
        if (active != 0u) {
            assert_int_equal(r.live.torque_switch, 5);
        }
        if (trip == NO_TRIP && active != 0u) {
            trip = (int32_t)t + 1;
            pos_trip = kr_pos(&r);
            first_bits = active;
            d = shows ? d_run : NO_TRIP;
        }
        /* the bridge obeys the highest active protection */
        const act_t want = prv_oracle(w, active, motor);
        if (want == ACT_FREE) {
            assert_int_equal(r.bridge.mode, KM_BRIDGE_FREE);
        } else if (want == ACT_BRAKE) {
            assert_int_equal(r.bridge.mode, KM_BRIDGE_BRAKE);
        } else if (want == ACT_HOLD) {
            /* holding where it tripped, or let go (free) once a higher
             * protection stopped the hold: never driving elsewhere */
            if (r.bridge.mode == KM_BRIDGE_PWM && t < t_end) {
                const int32_t dev = kr_pos(&r) - pos_trip;
                const int32_t adev = dev < 0 ? -dev : dev;
                hold_dev = adev > hold_dev ? adev : hold_dev;
                assert_true(adev <= (w->hold_tol != 0 ? w->hold_tol : HOLD_TOL_DDEG));
            } else if (r.bridge.mode != KM_BRIDGE_PWM) {
                assert_int_equal(r.bridge.mode, KM_BRIDGE_FREE);
            }
        }
        if (trip != NO_TRIP && (uint32_t)trip + 49u == t + 1u) {
            act_seen = prv_bridge_act(&r);
        }
        if (trip != NO_TRIP && (uint32_t)trip + 19u == t + 1u && active != 0u) {
            prv_motion_refused(&r);
        }
        if (trip != NO_TRIP && released == NO_TRIP && active == 0u) {
            released = (int32_t)t + 1;
        }
        if (released != NO_TRIP) {
            /* a released servo never drives by itself unless it holds */
            assert_int_equal(r.live.torque_switch, w->ts_after);
            if (w->ts_after != 2u) {
                assert_true(r.bridge.mode != KM_BRIDGE_PWM);
            }
            assert_int_equal(active, 0);
        }
    }

    int32_t rel_ms = NO_TRIP;
    if (released != NO_TRIP) {
        rel_ms = w->rel_from_trip ? released - trip : released - (int32_t)t_end;
    }
    char rel_txt[48];
    if (released == NO_TRIP) {
        snprintf(rel_txt, sizeof rel_txt, "%s", trip == NO_TRIP ? "-" : "held (not released)");
    } else {
        snprintf(rel_txt, sizeof rel_txt, "%s %+d ms%s",
                 w->rel == REL_CMD       ? "clear"
                 : w->rel == REL_DISABLE ? "0x32"
                                         : "auto",
                 rel_ms, w->rel_from_trip ? " from trip" : " from end");
    }
    char trip_txt[24];
    if (trip == NO_TRIP) {
        snprintf(trip_txt, sizeof trip_txt, "no trip");
    } else {
        snprintf(trip_txt, sizeof trip_txt, "%6d ms", trip);
    }
    printf("  %-66s trip %-9s 0x36=0x%X action %-5s", w->name, trip_txt, seen_bits, prv_act_name(act_seen));
    if (act_seen == ACT_HOLD) {
        printf(" (max %d.%d deg off)", hold_dev / 10, hold_dev % 10);
    }
    /* 0x64 at the end of the row (after the release, or 5 while still
     * held); a row that never trips has nothing to report */
    if (trip == NO_TRIP) {
        printf("  release %s  0x64 -> -", rel_txt);
    } else {
        printf("  release %s  0x64 -> %u", rel_txt, (unsigned)r.live.torque_switch);
    }
    /* the km_protect.h bound applies to an excursion sustained from a
     * clean start: steps and monotonic ramps, not noise or chatter; stall
     * excursions are not visible on one sensor (d stated in the rows) */
    const bool bound = trip != NO_TRIP && d != NO_TRIP && (first_bits & KM_PROT_STALL) == 0u &&
                       w->stim[0].period == 0u && w->stim[0].noise == 0 && !w->chatter;
    const int32_t t_ms = (int32_t)(km_protect_detect_us(&r.params, prv_first_bit(first_bits)) / 1000u);
    if (bound) {
        printf("  d=%d, trip-d = T+%d", d, trip - d - t_ms);
    }
    printf("\n");

    /* the row's expectations */
    if (w->trip_lo == NO_TRIP) {
        assert_int_equal(trip, NO_TRIP);
        assert_int_equal(seen_bits, 0);
        return;
    }
    assert_in_range(trip, w->trip_lo, w->trip_hi);
    assert_int_equal(seen_bits, w->bits);
    assert_int_equal(partial, w->partial);
    if (bound) {
        /* a sustained excursion from a clean start: the km_protect.h bound
         * [T, T + 1 tick] from its first sample on the sensor */
        assert_in_range(trip - d, t_ms, t_ms + 1);
    }
    assert_int_equal(act_seen, w->act);
    for (unsigned k = 0; k < 2; k++) {
        if (w->clear[k].mask != 0u) {
            assert_true(clears_done > k);
        }
    }
    if (w->rel == REL_NONE) {
        assert_int_equal(released, NO_TRIP);
    } else {
        assert_true(released != NO_TRIP);
        assert_in_range(rel_ms, w->rel_lo, w->rel_hi);
        assert_int_equal(r.live.torque_switch, w->ts_after);
    }
    if (w->move_target != 0) {
        /* the move stopped at the trip never resumes, held or not: the
         * shaft got no nearer its target (3.0 deg of play) */
        const int32_t left_trip = w->move_target - pos_trip;
        const int32_t left_end = w->move_target - kr_pos(&r);
        assert_true((left_end < 0 ? -left_end : left_end) >= (left_trip < 0 ? -left_trip : left_trip) - 30);
    }
    if (released != NO_TRIP && w->ts_after >= 2u) {
        /* released, held or armed: the next rotation command moves it */
        r.in.ext_torque_unm = 0;
        const int32_t from = kr_pos(&r);
        const int16_t to = (int16_t)(from > 0 ? from - 100 : from + 100);
        /* a shaft left on its end stop (past the travel) goes to the
         * travel's end: targets are clamped to it (km_servo_mode.h) */
        const int32_t at = km_servo_mode_clamp(&r.params, to);
        assert_true(kr_move(&r, KM_MOVE_SPEED, to, 0));
        kr_run(&r, 1000);
        assert_true(kr_pos(&r) >= at - 10 && kr_pos(&r) <= at + 10);
    }
}

static void test_s5_2_scenario_table(void **state)
{
    (void)state;
    assert_true(N_ROWS >= 40u);
    printf("  %u scenarios (docs/protocol.md §5.2, §4 bits 0-4) on the plant through km_control_step:\n",
           (unsigned)N_ROWS);
    for (size_t i = 0; i < N_ROWS; i++) {
        if (k_rows[i].hw != 0u) {
            prv_run_selftest(&k_rows[i]);
        } else {
            prv_run_row(&k_rows[i]);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_s5_2_scenario_table),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
