/* SPDX-License-Identifier: Apache-2.0 */
/* Protection supervisor: the four state machines, their timers and the
 * action of the highest active protection (contract in km_protect.h). */
#include "km_protect.h"

#include <string.h>

#include "km_axis.h"
#include "km_fixdiv.h"

#define PRV_N 4u
#define PRV_US_PER_100MS 100000u

/* §5.2 priority, highest first: voltage > temperature > current > stall. */
static const uint8_t s_priority[PRV_N] = {KM_PROT_VOLTAGE, KM_PROT_TEMPERATURE, KM_PROT_CURRENT,
                                          KM_PROT_STALL};

/* The bit number of a single protection bit (1, 2, 4 or 8 -> 0..3): the
 * index of its timer and of its two bits in 0x34. */
static uint8_t prv_bit_number(uint8_t bit)
{
    return (uint8_t)((bit >> 1) - (bit >> 3));
}

/* |v| as unsigned: exact for every v, INT32_MIN too (2^31). */
static uint32_t prv_mag(int32_t v)
{
    return v < 0 ? 0u - (uint32_t)v : (uint32_t)v;
}

void km_protect_init(km_protect_t *s)
{
    memset(s, 0, sizeof *s);
}

uint32_t km_protect_detect_us(const km_control_params_t *p, uint8_t bit)
{
    uint32_t t;
    if (bit == KM_PROT_CURRENT) {
        t = (uint32_t)p->current_time_100ms * PRV_US_PER_100MS;
    } else if (bit == KM_PROT_STALL) {
        t = (uint32_t)p->stall_time_100ms * PRV_US_PER_100MS;
    } else {
        t = KM_PROTECT_FIXED_TIME_US;
    }
    return t;
}

/* Is the excursion of each protection present? Temperature uses its
 * release threshold once tripped; stall needs the shaft to stay put. */
static uint8_t prv_excursions(km_protect_t *s, const km_protect_in_t *in, const km_control_params_t *p)
{
    uint8_t over = 0;
    const int32_t high_mv = (int32_t)p->voltage_high_v * 1000;
    const int32_t low_mv = (int32_t)p->voltage_low_v * 1000;
    if ((p->voltage_high_v != 0u && in->voltage_mv > high_mv) ||
        (p->voltage_low_v != 0u && in->voltage_mv < low_mv)) {
        over |= KM_PROT_VOLTAGE;
    }

    const int32_t hysteresis_c = (s->active & KM_PROT_TEMPERATURE) != 0u ? (int32_t)p->temp_hysteresis_c : 0;
    const int32_t temp_limit_c10 = ((int32_t)p->temp_trip_c - hysteresis_c) * 10;
    if (in->temperature_c10 >= temp_limit_c10) {
        over |= KM_PROT_TEMPERATURE;
    }

    if (prv_mag(in->current_ma) > p->current_trip_ma) {
        over |= KM_PROT_CURRENT;
    }

    if (prv_mag(in->drive_pwm) >= p->stall_pwm && p->stall_pwm != 0u) {
        if (!s->stall_anchored ||
            prv_mag(km_pos_diff(in->position, s->stall_anchor)) > KM_PROTECT_STALL_WINDOW) {
            /* first driven tick, or it moved on: timing starts again here */
            s->stall_anchor = in->position;
            if (s->stall_anchored) {
                s->timer_us[3] = 0u;
            }
            s->stall_anchored = true;
        }
        over |= KM_PROT_STALL;
    } else {
        s->stall_anchored = false;
    }
    return over;
}

static uint8_t prv_action_bits(const km_control_params_t *p, uint8_t bit)
{
    return (uint8_t)((p->prot_state >> (2u * prv_bit_number(bit))) & 3u);
}

/* Protection `bit`'s up/down timer `t` after this tick (`over`: its
 * excursion is present): trips at the detection time, releases
 * automatically when it counted back to 0 (0x33 bit clear). */
static uint32_t prv_time_one(km_protect_t *s, uint8_t bit, uint32_t t, bool over,
                             const km_control_params_t *p, uint32_t dt_us, km_protect_events_t *ev)
{
    if (over) {
        const uint32_t t_detect = km_protect_detect_us(p, bit);
        t += dt_us;
        if (t >= t_detect) {
            t = t_detect;
            if ((s->active & bit) == 0u) {
                s->active |= bit;
                ev->tripped |= bit;
            }
        }
    } else {
        t = t > dt_us ? t - dt_us : 0u;
        if (t == 0u && (s->active & bit) != 0u && (p->prot_release & bit) == 0u) {
            s->active &= (uint8_t)~bit; /* automatic release: absent for T */
            ev->released |= bit;
        }
    }
    return t;
}

/* The timer of each protection that is over, active or being timed (a
 * disabled one's timer dropped): prv_time_one. */
static void prv_time(km_protect_t *s, uint8_t over, uint8_t enabled, const km_control_params_t *p,
                     uint32_t dt_us, km_protect_events_t *ev)
{
    const uint8_t pending = (uint8_t)((over | s->active | s->timing) & enabled);
    uint8_t timing = 0;
#if KM_CONTROL_COMPACT
    for (unsigned i = 0; i < PRV_N; i++) { /* every index, one pass (flash); bit i's timer is timer_us[i] */
        const uint8_t bit = (uint8_t)(1u << i);
        uint32_t *const timer = &s->timer_us[i];
        if ((pending & bit) == 0u) {
            *timer = 0u; /* dropped if it was being timed, else 0 already (docs/footprint.md) */
            continue;
        }
        const uint32_t t = prv_time_one(s, bit, *timer, (over & bit) != 0u, p, dt_us, ev);
        *timer = t;
        if (t != 0u) {
            timing |= bit;
        }
    }
#else
    for (uint8_t dropped = (uint8_t)(s->timing & ~enabled); dropped != 0u;
         dropped &= (uint8_t)(dropped - 1u)) { /* the set bits only (tick instructions) */
        s->timer_us[prv_bit_number((uint8_t)(dropped & (0u - dropped)))] = 0u;
    }
    for (uint8_t rest = pending; rest != 0u; rest &= (uint8_t)(rest - 1u)) {
        const uint8_t bit = (uint8_t)(rest & (0u - rest));
        uint32_t *const timer = &s->timer_us[prv_bit_number(bit)];
        const uint32_t t = prv_time_one(s, bit, *timer, (over & bit) != 0u, p, dt_us, ev);
        *timer = t;
        if (t != 0u) {
            timing |= bit;
        }
    }
#endif
    s->timing = timing;
}

/* The action of the highest active protection (§5.2 priority): 0x34's
 * two bits; hold only in servo mode and only for current and stall. */
static km_prot_action_t prv_action(const km_protect_t *s, const km_control_params_t *p, bool servo_mode)
{
    if (s->active == 0u) {
        return KM_PROT_ACT_NONE; /* timing only: no protection acts yet */
    }
    for (uint8_t k = 0; k < PRV_N; k++) {
        const uint8_t bit = s_priority[k];
        if ((s->active & bit) == 0u) {
            continue;
        }
        const uint8_t a = prv_action_bits(p, bit);
        if (a == 0u) {
            return KM_PROT_ACT_FREE;
        }
        if (a == 1u || !servo_mode || bit == KM_PROT_VOLTAGE || bit == KM_PROT_TEMPERATURE) {
            return KM_PROT_ACT_BRAKE;
        }
        return KM_PROT_ACT_HOLD;
    }
    return KM_PROT_ACT_NONE;
}

KM_COMPACT_NOINLINE km_prot_action_t km_protect_step(km_protect_t *s, const km_protect_in_t *in,
                                                     const km_control_params_t *p, uint32_t dt_us,
                                                     km_protect_events_t *ev)
{
    ev->tripped = 0;
    ev->released = 0;

    /* A disabled protection is released at once and not watched. */
    const uint8_t enabled = (uint8_t)(p->prot_enable & KM_PROT_ALL);
    if ((s->active & (uint8_t)~enabled) != 0u) {
        ev->released |= (uint8_t)(s->active & (uint8_t)~enabled);
        s->active &= enabled;
    }

    const uint8_t over = (uint8_t)(prv_excursions(s, in, p) & enabled);
    s->over = over;
    if ((over | s->active | s->timing) == 0u) {
        return KM_PROT_ACT_NONE; /* the usual tick: nothing over, nothing being timed */
    }
    prv_time(s, over, enabled, p, dt_us, ev);
    return prv_action(s, p, in->servo_mode);
}

bool km_protect_clear(km_protect_t *s, uint8_t mask)
{
    mask &= KM_PROT_ALL;
    if ((s->active & mask & s->over) != 0u) {
        return false;
    }
    for (uint8_t i = 0; i < PRV_N; i++) {
        if ((s->active & mask & (1u << i)) != 0u) {
            s->timer_us[i] = 0u;
        }
    }
    s->active &= (uint8_t)~mask;
    return true;
}

km_prot_state_t km_protect_state(const km_protect_t *s, uint8_t bit)
{
    if ((s->active & bit) != 0u) {
        return KM_PROT_TRIPPED;
    }
    return s->timer_us[prv_bit_number(bit)] != 0u ? KM_PROT_PENDING : KM_PROT_NORMAL;
}
