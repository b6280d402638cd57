/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: the servo's sensors, already in engineering units. A real
 * board converts its ADC samples (potentiometer, shunt, supply divider, NTC)
 * here; a simulated board reads its plant. */
#ifndef KM_HAL_SENSORS_H
#define KM_HAL_SENSORS_H

#include <stdint.h>

typedef struct {
    int32_t position;        /* output shaft, 0.1 deg, before zero offsets */
    int32_t current_ma;      /* motor current, signed with the drive direction */
    int32_t voltage_mv;      /* supply */
    int32_t temperature_c10; /* motor/driver temperature, 0.1 degC */
    uint8_t faults;          /* hardware fault bits as register 0x35 (sensor faults) */
} km_sensors_t;

void km_hal_sensors_init(void);

/* Latest complete set of samples. Cheap: called once per control tick. */
void km_hal_sensors_read(km_sensors_t *out);

#endif
