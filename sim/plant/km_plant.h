/* SPDX-License-Identifier: Apache-2.0 */
/* Simulated servo plant: H-bridge, DC motor, gearbox, output load, position
 * sensor, supply and winding heat, integer-only and deterministic. The model,
 * its two configurations and how to run it: docs/plant.md. */
#ifndef KM_PLANT_H
#define KM_PLANT_H

#include <stdbool.h>
#include <stdint.h>

/* Overspeed guard, output shaft, m°/s (docs/plant.md "Notes on the code"). */
#define KM_PLANT_SPEED_MAX_MDPS 2000000

/* Potentiometer ADC full scale (12-bit, as on servo MCUs). */
#define KM_PLANT_POT_ADC_MAX 4095u
/* Counts per turn of the encoder product's single-turn absolute encoder. */
#define KM_PLANT_ENCODER_COUNTS 4096u

typedef enum {
    KM_PLANT_DRIVE = 0, /* PWM drive, in.pwm sets duty and direction */
    KM_PLANT_COAST = 1, /* all switches off: "free" */
    KM_PLANT_BRAKE = 2, /* both low sides on: short-circuit braking */
} km_plant_bridge_t;

/* Injectable faults (bit mask), for protection and hardware-fault tests. */
enum {
    KM_PLANT_FAULT_POT_OPEN = 1u << 0,   /* wiper open: ADC rails high, position reads +pot travel */
    KM_PLANT_FAULT_MOTOR_OPEN = 1u << 1, /* motor lead open: no current, no torque */
    KM_PLANT_FAULT_TEMP_OPEN = 1u << 2,  /* thermistor open: reads KM_PLANT_TEMP_OPEN_DC */
};
#define KM_PLANT_TEMP_OPEN_DC (-400) /* 0.1 °C: what an open NTC reads (-40.0 °C) */

/* What the realistic configuration adds to the ideal model (docs/plant.md). */
typedef struct {
    /* potentiometer through the board's 12-bit ADC */
    uint16_t pot_noise_mlsb;     /* noise of one ADC sample (wiper + ADC), sigma, 1/1000 LSB */
    uint8_t pot_oversample_log2; /* the board averages 2^n samples (STM32G0 hardware: 4 = 16x) */
    uint16_t pot_window_us;      /* time one oversampled reading spans (its lag is half of it) */
    /* single-turn magnetic encoder (encoder product) */
    uint16_t enc_noise_mcount; /* angle noise, sigma, 1/1000 count */
    /* gear train, output shaft */
    uint32_t stribeck_unm;       /* break-away friction above Coulomb at rest, µN·m */
    uint16_t stribeck_ddps;      /* Stribeck speed (the excess falls to half at it), 0.1 °/s */
    uint8_t eff_back_pct;        /* efficiency when the load drives the motor, % (gear_eff_pct is forward) */
    uint16_t backlash_mdeg;      /* total play, m° */
    uint32_t stiff_unm_per_mdeg; /* torsional stiffness of the gear train, µN·m per m° (> 0) */
    uint32_t mesh_damp_unm_per_dps; /* damping across that compliance, µN·m per °/s */
    uint32_t out_coulomb_unm;       /* output shaft's own friction (bushing, pot wiper), µN·m */
    /* supply shared with the other servos of one bus */
    uint16_t bus_r_mohm; /* source resistance shared by every servo on the bus, mΩ */
    uint8_t bus_servos;  /* servos drawing the same current together (>= 1) */
    /* H-bridge */
    uint16_t pwm_period_ns; /* PWM period, ns (> 0) */
    uint16_t dead_ns;       /* dead time lost per period, ns */
    uint16_t min_pulse_ns;  /* shorter on-pulses do not switch the bridge, ns */
    /* winding */
    uint16_t winding_r_mohm; /* copper part of motor_r_mohm at ambient_dc, mΩ */
    uint16_t tempco_ppm;     /* copper's resistance rise, ppm per °C */
    /* gravity: torque -gravity_unm * sin(angle - gravity_down_ddeg) on the output */
    uint32_t gravity_unm;      /* m·g·l of the arm, µN·m (0 = none) */
    int16_t gravity_down_ddeg; /* the output angle at which the arm hangs straight down, 0.1° */
    uint32_t seed;             /* noise generator seed (0 is taken as 1) */
} km_plant_real_t;

/* Parameters. Units are in each field's name and comment. */
typedef struct {
    uint16_t supply_mv;     /* supply open-circuit voltage, mV */
    uint16_t supply_r_mohm; /* supply + wiring internal resistance, mΩ (<= 4 * motor_r_mohm) */
    uint16_t motor_r_mohm;  /* winding + bridge on-resistance, mΩ (> 0) */
    uint16_t
        motor_ke_uv_s_rad; /* motor back-EMF constant, µV per rad/s at the motor; Kt = Ke (SI): µN·m per A */
    uint16_t gear_ratio;   /* motor turns per output turn */
    uint8_t gear_eff_pct;         /* gearbox efficiency, % (applied to torque in both directions) */
    uint32_t rotor_j_gmm2;        /* rotor inertia at the motor, g·mm² (1e-9 kg·m²) */
    uint32_t load_j_gmm2;         /* horn + load inertia at the output, g·mm² */
    uint32_t viscous_unm_per_dps; /* viscous friction at the output, µN·m per °/s */
    uint32_t coulomb_unm;         /* Coulomb (and static) friction at the output, µN·m */
    int16_t pot_travel_ddeg;      /* pot's electrical range ±this, 0.1° (> endstop); 0 = no pot */
    int16_t endstop_ddeg;         /* hard mechanical stops at ±this, 0.1°; 0 = free multi-turn */
    uint32_t thermal_r_mc_per_w;  /* winding-to-ambient thermal resistance, m°C per W */
    uint32_t thermal_c_mj_per_c;  /* winding + case heat capacity, mJ per °C */
    int16_t ambient_dc;           /* ambient and initial temperature, 0.1 °C */
    uint16_t substep_us;          /* integration sub-step, µs (1..1000) */
    const km_plant_real_t *real;  /* NULL: the ideal plant; else the realistic model */
} km_plant_config_t;

/* The named configurations of one servo (docs/plant.md). */
extern const km_plant_config_t km_plant_ideal_config;
extern const km_plant_config_t km_plant_realistic_config;
extern const km_plant_real_t km_plant_realistic_params; /* its .real, to copy and vary */
/* What the simulated boards and the tests run today: the ideal plant. */
#define km_plant_default_config km_plant_ideal_config

/* A configuration by name ("ideal", "realistic"); NULL for any other. */
const km_plant_config_t *km_plant_config_named(const char *name);

typedef struct {
    km_plant_bridge_t bridge;
    int16_t pwm;            /* −1000..1000 (clamped), sign = direction; DRIVE only */
    int32_t ext_torque_unm; /* external torque on the output shaft, µN·m, + = positive direction */
} km_plant_input_t;

/* The realistic model's state and gains (km_plant_real.c). Opaque. */
typedef struct {
    /* derived at init */
    int64_t kdt;           /* position step: (w * kdt) >> 16 is 0.1° Q32 per sub-step */
    int64_t accm_q24;      /* motor side: speed change (0.1 °/s Q16) per µN·m, Q24 */
    int64_t accl_q24;      /* output side: the same */
    int64_t stiff;         /* µN·m per 0.1° of deflection */
    int64_t damp_q16;      /* µN·m per 0.1 °/s, Q16: across the compliance */
    int64_t visc_q16;      /* µN·m per 0.1 °/s, Q16: the gear train's viscous friction */
    int64_t half_play_q32; /* half the backlash, 0.1° Q32 */
    int64_t rtemp_q32;     /* winding resistance rise, mΩ per µ°C, Q32 */
    int64_t heat_q40;      /* heating per sub-step: µ°C per (mA² · mΩ), Q40 */
    int64_t adc_gain_q24;  /* ADC LSB per 0.1°, Q24 */
    int64_t lag_q32;       /* the ADC reading's lag, s, Q32 */
    int64_t inv_ws_q16;    /* 1 / Stribeck speed (0.1 °/s), Q16 */
    int32_t ke_q32;        /* back-EMF: mV per (0.1 °/s Q16), Q32 */
    int32_t kt_q16;        /* motor torque at the output, µN·m per mA, Q16 (no efficiency) */
    int32_t mu_fwd_q16;    /* mesh loss per µN·m transmitted, motor driving the load, Q16 */
    int32_t mu_back_q16;   /* the same, load driving the motor, Q16 */
    int32_t noise_pot_q8;  /* ADC noise: (Q16 LSB) per unit of the generator, Q8 */
    int32_t noise_enc_q8;  /* encoder noise: (Q16 count) per unit of the generator, Q8 */
    int32_t dead_pm;       /* dead time, per mille of the period */
    int32_t min_pm;        /* minimum pulse, per mille of the period */
    int32_t r_fixed_mohm;  /* bridge and brushes: motor_r minus the copper */
    int32_t src_mohm;      /* supply_r + bus_servos * bus_r */
    /* updated once per km_plant_step (the winding heats slowly) */
    int32_t r_mohm;   /* winding + bridge now */
    int32_t g_q16;    /* 1 / r_mohm: mA per mV, Q16 */
    int32_t rint_q12; /* src_mohm / r_mohm, Q12 */
    /* state */
    int64_t th_q32;   /* output shaft, 0.1° Q32 (multi-turn) */
    int64_t defl_q32; /* motor side minus output shaft, 0.1° Q32: play and deflection */
    int64_t enc_q32;  /* output angle within one turn, 0.1° Q32, in [0, 3600 << 32) */
    int32_t wl_q16;   /* output shaft speed, 0.1 °/s Q16 */
    int32_t wm_q16;   /* motor side speed referred to the output, 0.1 °/s Q16 */
    uint32_t rng;     /* xorshift32 state */
    /* the sensors as the board last sampled them (end of each step) */
    int16_t pos_ddeg; /* potentiometer through the ADC and the board's conversion */
    uint16_t adc;     /* the oversampled 12-bit ADC reading */
    uint16_t enc;     /* encoder counts */
} km_plant_real_state_t;

/* State and derived gains. Treat as opaque; read through the functions below. */
typedef struct {
    const km_plant_config_t *cfg;
    /* derived at init (fixed-point gains for the fixed sub-step) */
    uint32_t sub_us;  /* effective sub-step, µs */
    int32_t ke_q24;   /* back-EMF at output: mV per mdeg/s, Q24 */
    int32_t kt_q16;   /* torque at output: µN·m per mA, Q16 */
    int32_t g_q16;    /* motor conductance: mA per mV, Q16 */
    int32_t rint_q12; /* R_int / R, Q12 */
    int64_t visc_q16; /* viscous friction: µN·m per m°/s, Q16 */
    int64_t acc_q24;  /* speed change per sub-step: mdeg/s per µN·m, Q24 */
    int64_t heat_q30; /* heating per sub-step: µ°C per mW, Q30 */
    int64_t cool_q30; /* cooling per sub-step: fraction of (T - T_amb), Q30 */
    /* settable environment */
    int32_t supply_mv;
    int32_t ambient_uc; /* µ°C */
    uint32_t faults;
    /* state */
    int32_t pos_ddeg;        /* output position, whole 0.1° part (multi-turn, wraps at int32) */
    int32_t pos_rem_ndeg;    /* output position remainder, nano-degrees, |rem| < 1e8 */
    int32_t speed_mdps;      /* output speed, milli-degrees per second */
    int32_t current_ma;      /* motor current, mA, signed (+ drives positive) */
    int32_t supply_ma;       /* current drawn from the supply, mA (signed) */
    int32_t bus_mv;          /* voltage at the servo's supply terminals, mV */
    int32_t temp_uc;         /* winding temperature, µ°C */
    uint32_t carry_us;       /* time not yet integrated (< sub_us) */
    uint32_t time_ms;        /* simulated time, ms (wraps after ~49 days) */
    uint32_t time_us_part;   /* µs part of time_ms */
    int32_t step_peak_ma;    /* the largest |current_ma| of the last km_plant_step's sub-steps */
    km_plant_real_state_t r; /* the realistic model (cfg->real != NULL) */
} km_plant_t;

/* What a restart of the servo's MCU leaves as it is (docs/plant.md "Notes on the code"). */
typedef struct {
    int32_t pos_ddeg;
    int32_t pos_rem_ndeg;
    int32_t speed_mdps;
    int32_t temp_uc;
    int32_t supply_mv;
    int32_t ambient_uc;
    uint32_t faults;
    uint32_t time_ms; /* the simulated world's clock goes on too */
} km_plant_physics_t;

void km_plant_get_physics(const km_plant_t *p, km_plant_physics_t *out);
/* Restores what km_plant_get_physics gave, clamped as the setters clamp. */
void km_plant_set_physics(km_plant_t *p, const km_plant_physics_t *in);

/* Sets up a plant at rest at 0, ambient temperature, full supply; false on a bad cfg. */
bool km_plant_init(km_plant_t *p, const km_plant_config_t *cfg);

/* Advance the simulation by dt_us with the bridge input held constant. */
void km_plant_step(km_plant_t *p, const km_plant_input_t *in, uint32_t dt_us);

/* Environment and test hooks. */
void km_plant_set_supply_mv(km_plant_t *p, int32_t mv);  /* open-circuit supply, mV (>= 0) */
void km_plant_set_ambient_dc(km_plant_t *p, int16_t dc); /* ambient, 0.1 °C */
void km_plant_set_temp_dc(km_plant_t *p,
                          int32_t dc); /* winding temperature now, 0.1 °C (a test's thermal profile) */
void km_plant_set_position_ddeg(km_plant_t *p, int32_t ddeg); /* teleport shaft (at rest) */
void km_plant_set_faults(km_plant_t *p, uint32_t faults);     /* KM_PLANT_FAULT_* mask */

/* Readings: what the board's sensors would report (docs/plant.md "Selecting one"). */
int16_t km_plant_position_ddeg(const km_plant_t *p); /* potentiometer, 0.1°, clamped to ±pot travel */
uint16_t km_plant_pot_adc(const km_plant_t *p); /* same as 12-bit ADC counts, 0 = -travel, 4095 = +travel */
int32_t km_plant_turns_ddeg(
    const km_plant_t *p); /* multi-turn shaft position, 0.1°, unclamped (the truth, no sensor) */
int64_t km_plant_shaft_udeg(const km_plant_t *p); /* the same in µ° (for measuring, not a sensor) */
uint16_t
km_plant_encoder_counts(const km_plant_t *p); /* single-turn absolute encoder, 0..KM_PLANT_ENCODER_COUNTS-1 */
int32_t km_plant_speed_dps(const km_plant_t *p);  /* output speed, °/s (rounded) */
int32_t km_plant_speed_mdps(const km_plant_t *p); /* output speed, m°/s */
int32_t km_plant_current_ma(const km_plant_t *p); /* motor current, mA, signed; a shunt reads its magnitude */
int32_t km_plant_step_peak_ma(
    const km_plant_t *p); /* the largest |motor current| any sub-step of the last step had, mA */
int32_t km_plant_supply_ma(const km_plant_t *p);  /* supply current, mA */
int32_t km_plant_voltage_mv(const km_plant_t *p); /* supply terminal voltage, mV */
int32_t km_plant_temp_dc(const km_plant_t *p);    /* winding temperature, 0.1 °C (rounded) */
int32_t km_plant_temp_c(const km_plant_t *p);     /* winding temperature, °C (rounded) */
uint32_t km_plant_time_ms(const km_plant_t *p);   /* simulated time since km_plant_init, ms */
bool km_plant_at_endstop(const km_plant_t *p);    /* shaft resting on a mechanical stop */

#endif /* KM_PLANT_H */
