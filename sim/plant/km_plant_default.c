/* Default plant parameters: a 20 kg·cm-class hobby serial bus servo on a 2S
 * Li-ion pack. Derivation of the numbers (output shaft unless said otherwise):
 *   - datasheet targets at 7.4 V: no-load 0.16 s/60° (375 °/s), stall torque
 *     ~20 kg·cm (1.96 N·m), stall current ~2.5 A.
 *   - stall current: I = V / (R + R_int) = 7.4 V / (2.8 + 0.15) Ω = 2.5 A.
 *   - gear ratio 300: 375 °/s at the output = 1963 rad/s (18 750 rpm) at the
 *     motor, so Ke = 7.4 V / 1963 rad/s = 3.77 mV·s/rad (Kt = 3.77 mN·m/A).
 *   - stall torque: Kt * I * ratio * efficiency = 3.77e-3 * 2.5 * 300 * 0.70
 *     = 1.98 N·m = 20.2 kg·cm.
 *   - friction: 0.03 N·m Coulomb + 50 µN·m per °/s viscous, so no-load
 *     current is ~60 mA and no-load speed ~366 °/s (0.164 s/60°).
 *   - inertia: rotor 1e-7 kg·m² reflected through 300² = 9e-3 kg·m², plus a
 *     1e-5 kg·m² horn; mechanical time constant J R / (Ke Kt ratio² eff)
 *     ~ 28 ms, as measured on such servos.
 *   - pot: its ADC spans ±165° (0 and full scale at the ends of its
 *     electrical range), hard stops at ±150°, the product's travel ±135°
 *     (boards/sim-common/km_sim_product.c). A sound pot reads at most ±150°,
 *     ADC 186..3909, clear of the rails; an open wiper reads the rail,
 *     +165°, beyond anything the mechanics can give. A pot whose electrical
 *     range ended inside the stops would read a shaft resting on a stop as
 *     a rail, an open wiper and a stop alike.
 *   - heat: R_th 15 °C/W, C_th 5 J/°C (tau 75 s); a stalled motor (17.5 W)
 *     heads for +260 °C, which is why servos have stall and heat protection.
 */
#include "km_plant.h"

const km_plant_config_t km_plant_default_config = {
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
