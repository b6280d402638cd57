/* SPDX-License-Identifier: Apache-2.0 */
/* Self-test (docs/protocol.md §5.2 0x35, status bit 4): sensor plausibility
 * over the first KM_SELFTEST_SAMPLES ticks (a majority of failed samples
 * fails a check), position and temperature supervised at run time on
 * up/down timers, and an open motor lead whenever driven. Rules:
 * docs/protocol-decisions.md "Protections"; docs/control-design.md. */
#ifndef KM_SELFTEST_H
#define KM_SELFTEST_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_sensors.h"
#include "km_params.h"
#include "km_status.h"

#define KM_SELFTEST_SAMPLES 16u /* ticks of the power-on check */
#define KM_SELFTEST_FREE_MIN 4u /* bridge-free samples the offset check needs */
#define KM_SELFTEST_NTC_OPEN_C10 (-300)
#define KM_SELFTEST_NTC_SHORT_C10 1500
#define KM_SELFTEST_SUPPLY_MIN_MV 2000
#define KM_SELFTEST_SUPPLY_MAX_MV 40000
#define KM_SELFTEST_CURRENT_OFFSET_MA 200
#define KM_SELFTEST_MOTOR_PWM 300
#define KM_SELFTEST_MOTOR_MA 10
#define KM_SELFTEST_MOTOR_US 500000u
#define KM_SELFTEST_POS_RUN_US 20000u   /* run-time position check: a wiper lost while holding */
#define KM_SELFTEST_TEMP_RUN_US 500000u /* run-time temperature check (heat is slow) */

typedef struct {
    uint8_t samples;        /* power-on samples taken */
    uint8_t fails[4];       /* per power-on check: samples that failed */
    uint8_t free_samples;   /* samples taken with the bridge free (the current check's) */
    uint8_t faults;         /* 0x35 bits found so far (latched) */
    uint32_t motor_open_us; /* driven without current, continuous */
    uint32_t run_bad_us[2]; /* run-time up/down timers: position, temperature */
} km_selftest_t;

void km_selftest_init(km_selftest_t *t);

/* One tick on the PWM the bridge drove (0 unless driving); returns the
 * 0x35 bits found so far. */
uint8_t km_selftest_step(km_selftest_t *t, const km_sensors_t *in, const km_control_params_t *p,
                         int32_t drive_pwm, bool bridge_free, uint32_t dt_us);

/* The power-on checks have all their samples. */
static inline bool km_selftest_done(const km_selftest_t *t)
{
    return t->samples >= KM_SELFTEST_SAMPLES;
}

#endif
