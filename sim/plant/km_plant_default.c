/* SPDX-License-Identifier: Apache-2.0 */
/* The plant's named configurations: "ideal" and "realistic", one 20 kg·cm-class
 * hobby servo on a 2S pack (its numbers derived in docs/plant.md). */
#include "km_plant.h"

#include <stddef.h>
#include <string.h>

const km_plant_config_t km_plant_ideal_config = {
    .supply_mv = 7400,
    .supply_r_mohm = 150,
    .motor_r_mohm = 2800,
    .motor_ke_uv_s_rad = 3770,
    .gear_ratio = 300,
    .gear_eff_pct = 70,
    .rotor_j_gmm2 = 100,
    .load_j_gmm2 = 10000,
    .viscous_unm_per_dps = 50,
    .coulomb_unm = 30000,
    .pot_travel_ddeg = 1650,
    .endstop_ddeg = 1500,
    .thermal_r_mc_per_w = 15000,
    .thermal_c_mj_per_c = 5000,
    .ambient_dc = 250,
    .substep_us = 250,
};

/* "realistic": the same servo as a board and a bench see it (docs/plant.md). */
const km_plant_real_t km_plant_realistic_params = {
    .pot_noise_mlsb = 1500,       /* 1.5 LSB per sample: ADC + wiper + PWM pick-up */
    .pot_oversample_log2 = 4,     /* boards/stm32g031/adc.c: 16x, >> 4 */
    .pot_window_us = 350,         /* adc.c: 16 x 4 channels x 5.4 µs */
    .enc_noise_mcount = 400,      /* 0.4 count (0.035°) */
    .stribeck_unm = 15000,        /* break-away 1.5x Coulomb */
    .stribeck_ddps = 10,          /* 1 °/s at the output (5 rad/s at the motor) */
    .eff_back_pct = 57,           /* (2 eff - 1) / eff with eff = 0.70 */
    .backlash_mdeg = 400,         /* 0.4°: a metal-geared hobby servo */
    .stiff_unm_per_mdeg = 2000,   /* 115 N·m/rad: stall torque deflects ~1° */
    .mesh_damp_unm_per_dps = 180, /* ~0.15 of critical for the output side */
    .out_coulomb_unm = 5000,      /* output bushing and pot wiper */
    .bus_r_mohm = 100,            /* 2S pack + shared harness */
    .bus_servos = 4,              /* four servos moving together */
    .pwm_period_ns = 50000,       /* 20 kHz (boards/stm32g031/motor.c) */
    .dead_ns = 400,
    .min_pulse_ns = 600,
    .winding_r_mohm = 2400, /* of the 2.8 Ω: the rest is bridge and brushes */
    .tempco_ppm = 3930,     /* copper */
    .gravity_unm = 0,       /* no arm on the bench */
    .gravity_down_ddeg = 0,
    .seed = 0x5EED2024u,
};

const km_plant_config_t km_plant_realistic_config = {
    .supply_mv = 7400,
    .supply_r_mohm = 60, /* the servo's own lead and connectors */
    .motor_r_mohm = 2800,
    .motor_ke_uv_s_rad = 3770,
    .gear_ratio = 300,
    .gear_eff_pct = 70,
    .rotor_j_gmm2 = 100,
    .load_j_gmm2 = 10000,
    .viscous_unm_per_dps = 50,
    .coulomb_unm = 30000,
    .pot_travel_ddeg = 1650, /* as the ideal: the ADC spans +-165 deg, stops at +-150 */
    .endstop_ddeg = 1500,
    .thermal_r_mc_per_w = 15000,
    .thermal_c_mj_per_c = 5000,
    .ambient_dc = 250,
    .substep_us = 100, /* the gear spring needs it (halved further if not stable) */
    .real = &km_plant_realistic_params,
};

/* A configuration by name; NULL for an unknown one. */
const km_plant_config_t *km_plant_config_named(const char *name)
{
    if (name == NULL) {
        return NULL;
    }
    if (strcmp(name, "ideal") == 0) {
        return &km_plant_ideal_config;
    }
    if (strcmp(name, "realistic") == 0) {
        return &km_plant_realistic_config;
    }
    return NULL;
}
