/* SPDX-License-Identifier: Apache-2.0 */
/* Multi-turn position from a single-turn encoder (km_turn_counter.h). */
#include "km_turn_counter.h"

#define KM_DDEG_PER_TURN 3600u

static uint16_t prv_in_range(const km_turn_counter_t *t, uint16_t raw)
{
    return (uint16_t)(raw < t->counts ? raw : raw % t->counts);
}

void km_turn_counter_init(km_turn_counter_t *t, uint16_t counts_per_turn, uint16_t raw)
{
    t->counts = counts_per_turn < 2u ? 2u : counts_per_turn;
    t->turns = 0;
    t->last = prv_in_range(t, raw);
}

int32_t km_turn_counter_update(km_turn_counter_t *t, uint16_t raw)
{
    raw = prv_in_range(t, raw);
    /* more than half a turn forward is a wrap backwards, and vice versa */
    const int32_t step = (int32_t)raw - (int32_t)t->last;
    const int32_t half = (int32_t)(t->counts / 2u);
    if (step > half) {
        t->turns--;
    } else if (step < -half) {
        t->turns++;
    }
    t->last = raw;
    /* Unsigned so that the wrap at int32 is defined, as 0x46's is. */
    const uint32_t within = ((uint32_t)raw * KM_DDEG_PER_TURN + t->counts / 2u) / t->counts;
    return (int32_t)((uint32_t)t->turns * KM_DDEG_PER_TURN + within);
}
