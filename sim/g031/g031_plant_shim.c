/* SPDX-License-Identifier: Apache-2.0 */
/* The plant (sim/plant, the integer model host-sim and the QEMU image run)
 * as a host shared library for the virtual G031 (sim/g031/g031_plant.py
 * builds it with the host's cc and calls it through ctypes): one plant per
 * servo, stepped to each ADC conversion with the bridge as TIM3 drives it. */
#include <stddef.h>
#include <stdint.h>

#include "km_plant.h"

/* One servo: its plant and the configuration it runs on (a copy of a
 * named one, with this servo's end stops). */
typedef struct {
    km_plant_t plant;
    km_plant_config_t cfg;
} g031_servo_t;

/* Bytes a plant takes (the caller allocates them). */
size_t g031_plant_size(void)
{
    return sizeof(g031_servo_t);
}

/* A plant at rest with the named configuration and its hard stops at
 * +-endstop_ddeg (docs/virtual-g031.md "The plant"); 0 on success. */
int g031_plant_init(g031_servo_t *s, const char *config_name, int32_t endstop_ddeg)
{
    const km_plant_config_t *cfg = km_plant_config_named(config_name);
    if (cfg == NULL || endstop_ddeg <= 0 || endstop_ddeg >= cfg->pot_travel_ddeg) {
        return -1;
    }
    s->cfg = *cfg;
    s->cfg.endstop_ddeg = (int16_t)endstop_ddeg;
    return km_plant_init(&s->plant, &s->cfg) ? 0 : -1;
}

/* Advances the plant by dt_us with the bridge held (0 drive, 1 coast, 2 brake). */
void g031_plant_step(km_plant_t *p, int32_t bridge, int32_t pwm, int32_t ext_torque_unm, uint32_t dt_us)
{
    km_plant_input_t in = {(km_plant_bridge_t)bridge, (int16_t)pwm, ext_torque_unm};
    km_plant_step(p, &in, dt_us);
}

/* The physical quantities the board's sensors see: pot position (0.1 deg),
 * motor current (mA, signed), supply terminal voltage (mV), winding
 * temperature (0.1 degC). */
void g031_plant_read(const km_plant_t *p, int32_t out[4])
{
    out[0] = km_plant_position_ddeg(p);
    out[1] = km_plant_current_ma(p);
    out[2] = km_plant_voltage_mv(p);
    out[3] = km_plant_temp_dc(p);
}

/* One bench scenario event (boards/sim-common/km_sim_scenario.h keys):
 * 1 supply_mv, 2 ambient_dc, 4 faults, 5 temp_dc; 3 (the load) is the
 * caller's torque input. */
void g031_plant_event(km_plant_t *p, int32_t key, int32_t value)
{
    if (key == 1) {
        km_plant_set_supply_mv(p, value);
    } else if (key == 2) {
        km_plant_set_ambient_dc(p, (int16_t)value);
    } else if (key == 4) {
        km_plant_set_faults(p, (uint32_t)value);
    } else if (key == 5) {
        km_plant_set_temp_dc(p, value);
    }
}

/* The plant's clock: ms since its power-on (a scenario runs on it). */
uint32_t g031_plant_time_ms(const km_plant_t *p)
{
    return km_plant_time_ms(p);
}
