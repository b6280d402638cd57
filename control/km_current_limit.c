/* SPDX-License-Identifier: Apache-2.0 */
/* Current limit: an integral PWM cap (contract in km_current_limit.h). */
#include "km_current_limit.h"

#include "km_fixdiv.h"

#define PRV_PWM_MAX KM_CURRENT_LIMIT_OPEN

void km_current_limit_init(km_current_limit_t *l)
{
    l->cap = PRV_PWM_MAX;
}

int32_t km_current_limit_step(km_current_limit_t *l, int32_t current_ma, uint32_t limit_ma)
{
    if (limit_ma == 0u) {
        l->cap = PRV_PWM_MAX;
        return l->cap;
    }
    const int32_t i = current_ma < 0 ? -current_ma : current_ma;
    const int32_t lim = limit_ma > 100000u ? 100000 : (int32_t)limit_ma;
    const int32_t step = (lim - i) / KM_CURRENT_LIMIT_DIV; /* a power of 2: no divide call */
    l->cap = km_clamp(l->cap + step, 0, PRV_PWM_MAX);
    return l->cap;
}
