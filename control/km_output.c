/* SPDX-License-Identifier: Apache-2.0 */
/* Output stage (see km_output.h). */
#include "km_output.h"

#include "km_fixdiv.h"

km_bridge_t km_output_bridge(km_bridge_mode_t mode, int32_t pwm_user, int32_t pwm_limit, bool reverse)
{
    km_bridge_t b = {mode, 0};
    if (mode != KM_BRIDGE_PWM) {
        return b;
    }
    if (pwm_limit > 1000) {
        pwm_limit = 1000;
    } else if (pwm_limit < 0) {
        pwm_limit = 0;
    }
    int32_t v = km_sat(pwm_user, pwm_limit);
    b.pwm = (int16_t)(reverse ? -v : v);
    return b;
}

int32_t km_output_pwm_reported(const km_bridge_t *b)
{
    if (b->mode != KM_BRIDGE_PWM) {
        return 0;
    }
    return b->pwm < 0 ? -b->pwm : b->pwm;
}
