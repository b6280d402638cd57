/* SPDX-License-Identifier: Apache-2.0 */
/* Power-on self-test, the run-time sensor supervision and the motor check
 * (contract in km_selftest.h). */
#include "km_selftest.h"

#include <string.h>

#include "km_fixdiv.h"

enum { PRV_POS, PRV_TEMP, PRV_VOLT, PRV_CURR, PRV_N };

static const uint8_t s_bit[PRV_N] = {KM_HW_POSITION, KM_HW_TEMPERATURE, KM_HW_VOLTAGE, KM_HW_CURRENT};
/* The run-time checks' times, by index (position, temperature). */
static const uint32_t s_run_us[2] = {KM_SELFTEST_POS_RUN_US, KM_SELFTEST_TEMP_RUN_US};

static int32_t prv_abs(int32_t v)
{
    return v < 0 ? -v : v;
}

void km_selftest_init(km_selftest_t *t)
{
    memset(t, 0, sizeof *t);
}

/* A position reading the mechanics cannot give: an open or shorted wiper
 * (potentiometer products; an encoder has no rail). */
static bool prv_position_bad(const km_sensors_t *in, const km_control_params_t *p)
{
    return km_params_variant(p) == KM_VARIANT_POTENTIOMETER &&
           (in->position < p->pos_read_min || in->position > p->pos_read_max);
}

/* A temperature reading no servo has: an open or shorted NTC. */
static bool prv_temperature_bad(const km_sensors_t *in)
{
    return in->temperature_c10 < KM_SELFTEST_NTC_OPEN_C10 || in->temperature_c10 > KM_SELFTEST_NTC_SHORT_C10;
}

/* One power-on sample; `sensors_bad` has the position and temperature
 * checks' bits (1 << PRV_POS, 1 << PRV_TEMP). */
static void prv_power_on_sample(km_selftest_t *t, const km_sensors_t *in, unsigned sensors_bad,
                                bool bridge_free)
{
    const unsigned bad =
        sensors_bad |
        (in->voltage_mv < KM_SELFTEST_SUPPLY_MIN_MV || in->voltage_mv > KM_SELFTEST_SUPPLY_MAX_MV
             ? 1u << PRV_VOLT
             : 0u) |
        (bridge_free && prv_abs(in->current_ma) > KM_SELFTEST_CURRENT_OFFSET_MA ? 1u << PRV_CURR : 0u);
    if (bridge_free) {
        t->free_samples++;
    }
    for (unsigned i = 0; i < PRV_N; i++) {
        t->fails[i] = (uint8_t)(t->fails[i] + ((bad >> i) & 1u));
    }
    t->samples++;
    if (t->samples == KM_SELFTEST_SAMPLES) {
        for (unsigned i = 0; i < PRV_N; i++) {
            const unsigned n = i == PRV_CURR ? t->free_samples : KM_SELFTEST_SAMPLES;
            if (n >= KM_SELFTEST_FREE_MIN && t->fails[i] > n / 2u) {
                t->faults |= s_bit[i];
            }
        }
    }
}

/* One run-time check's up/down timer: the fault once it reaches the
 * check's time (km_selftest.h). */
static void prv_run_check(km_selftest_t *t, unsigned i, bool bad, uint32_t dt_us)
{
    uint32_t timer = t->run_bad_us[i];
    if (bad) {
        timer += dt_us;
        if (timer >= s_run_us[i]) {
            timer = s_run_us[i];
            t->faults |= s_bit[i];
        }
    } else {
        timer = timer > dt_us ? timer - dt_us : 0u;
    }
    t->run_bad_us[i] = timer;
}

KM_COMPACT_NOINLINE uint8_t km_selftest_step(km_selftest_t *t, const km_sensors_t *in,
                                             const km_control_params_t *p, int32_t drive_pwm,
                                             bool bridge_free, uint32_t dt_us)
{
    t->faults |= in->faults; /* what the hal's drivers flag, at any time */
    const unsigned bad =
        (prv_position_bad(in, p) ? 1u << PRV_POS : 0u) | (prv_temperature_bad(in) ? 1u << PRV_TEMP : 0u);
    if (!km_selftest_done(t)) {
        prv_power_on_sample(t, in, bad, bridge_free);
    } else if (bad != 0u || (t->run_bad_us[PRV_POS] | t->run_bad_us[PRV_TEMP]) != 0u) {
        /* the usual tick (both sound, nothing being timed) skips this */
        prv_run_check(t, PRV_POS, (bad & (1u << PRV_POS)) != 0u, dt_us);
        prv_run_check(t, PRV_TEMP, (bad & (1u << PRV_TEMP)) != 0u, dt_us);
    }
    if (prv_abs(drive_pwm) >= KM_SELFTEST_MOTOR_PWM && prv_abs(in->current_ma) < KM_SELFTEST_MOTOR_MA) {
        t->motor_open_us += dt_us;
        if (t->motor_open_us >= KM_SELFTEST_MOTOR_US) {
            t->faults |= KM_HW_MOTOR;
            t->motor_open_us = KM_SELFTEST_MOTOR_US;
        }
    } else {
        t->motor_open_us = 0u;
    }
    return t->faults;
}
