/* SPDX-License-Identifier: Apache-2.0 */
/* Power-on self-test (docs/protocol.md §5.2 0x35, status bit 4): sensor
 * plausibility over the first KM_SELFTEST_SAMPLES control ticks after
 * boot, with the bridge off; the same plausibility of the position and
 * temperature sensors supervised at run time; and one check that needs the
 * motor driven, made whenever it is (an open motor lead). Pure,
 * fixed-point.
 *
 * A power-on check fails only when more than half of its samples fail, so
 * one noisy sample never raises a fault. Power-on checks (bits of 0x35):
 *   5 position sensor  potentiometer product: the reading is outside what
 *                      the mechanics can give (pos_read_min/max of the
 *                      product: its end stops and a tolerance, inside the
 *                      pot's electrical range), i.e. an open or shorted
 *                      wiper reading a rail. A shaft resting on or past the
 *                      end of its travel, up to its stop, is no fault:
 *                      motion commands bring it back. And whatever the
 *                      hal's sensor driver flags;
 *   2 temperature      below -30.0 degC (an open NTC) or above 150.0 degC
 *                      (a shorted one);
 *   3 voltage sensor   supply reads below 2.0 V (the MCU runs, so the
 *                      divider or its ADC input is broken) or above 40.0 V;
 *   4 current sensor   more than 200 mA with the bridge free (offset): only
 *                      the samples taken with the bridge free count, and
 *                      at least 4 of them are needed (a servo commanded
 *                      in its first milliseconds skips this check);
 * At run time (after the power-on samples):
 *   5, 2               the position and temperature checks above, each on
 *                      an up/down timer as the protections' (km_protect.h):
 *                      +1 tick while the reading is implausible, -1 while
 *                      it is plausible (not below 0); a fault when it
 *                      reaches its time T: 20 ms for the position (the
 *                      loop drives on a lost wiper's reading: it must stop
 *                      soon), 500 ms for the temperature (heat is slow).
 *                      So a sensor that fails for good is found T after it
 *                      failed, one noisy sample never is, and one that
 *                      chatters is only when it is bad more than half the
 *                      time;
 *   6 motor            |PWM| >= 300 with |current| < 10 mA for 500 ms: a
 *                      driven motor that draws nothing is an open lead.
 * Bits 1 (memory: the store found damage) and 0 (crystal) come from the
 * app and the board; bit 7 from the hal. The dispatcher latches every bit
 * until restart and refuses more motion while any is set (§5.2); a
 * request for less motion is always taken (km_request.h). */
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

/* One tick. `drive_pwm` is the PWM the bridge drove during the tick
 * (0 when free or braked), `bridge_free` whether it was free. Returns the
 * 0x35 bits found so far. */
uint8_t km_selftest_step(km_selftest_t *t, const km_sensors_t *in, const km_control_params_t *p,
                         int32_t drive_pwm, bool bridge_free, uint32_t dt_us);

/* The power-on checks have all their samples. */
static inline bool km_selftest_done(const km_selftest_t *t)
{
    return t->samples >= KM_SELFTEST_SAMPLES;
}

#endif
