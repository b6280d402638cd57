/* SPDX-License-Identifier: Apache-2.0 */
/* Template: the sensors in engineering units (km_hal_sensors.h). */
#include "km_hal_sensors.h"

/* ADC channels (potentiometer, shunt, supply divider, NTC), ideally sampled
 * by a timer-triggered scan into a buffer, so reading is a copy. */
void km_hal_sensors_init(void)
{
}

/* Convert the latest complete scan: position 0.1 deg, current mA, supply
 * mV, temperature 0.1 degC, fault bits as register 0x35. */
void km_hal_sensors_read(km_sensors_t *out)
{
    *out = (km_sensors_t){0};
}
