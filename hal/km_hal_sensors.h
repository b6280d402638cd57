/* SPDX-License-Identifier: Apache-2.0 */
/* HAL contract: the sensors, in engineering units. */
#ifndef KM_HAL_SENSORS_H
#define KM_HAL_SENSORS_H

#include <stdint.h>

typedef struct {
    int32_t position;        /* output shaft, 0.1 deg, before zero offsets */
    int32_t current_ma;      /* motor, signed as the drive */
    int32_t voltage_mv;      /* supply */
    int32_t temperature_c10; /* 0.1 degC */
    uint8_t faults;          /* sensor faults, 0x35 bits */
} km_sensors_t;

void km_hal_sensors_init(void);

/* The latest samples; called every control tick. */
void km_hal_sensors_read(km_sensors_t *out);

#endif
