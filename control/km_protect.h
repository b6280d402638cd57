/* SPDX-License-Identifier: Apache-2.0 */
/* Protection supervisor (docs/protocol.md §5.2, status bits 0-3 of §4): voltage,
 * temperature, current and stall, one state machine each, run every control
 * tick after sensing and before the output stage. Pure, fixed-point.
 *
 * Per protection: NORMAL -> PENDING (the excursion is being timed) ->
 * TRIPPED (0x36 bit set, its 0x34 action applied) -> released, NORMAL.
 *
 * Filtering: an up/down timer per protection. Each tick the excursion is
 * present it counts up by the tick, each tick it is absent it counts down
 * (not below 0); it trips when the timer reaches the detection time T
 * (voltage, temperature: 3 s fixed; current, stall: 0x3E/0x3F x 100 ms;
 * 0 = one tick). So:
 *   - an excursion lasting less than T from a clean start never trips;
 *     one noisy sample adds one tick and is forgotten one tick later;
 *   - a sustained excursion trips after exactly T (from a clean start; at
 *     most T after it begins in any case), i.e. within [T, T + 1 tick] of
 *     its first sample when the timer read 0;
 *   - an excursion that chatters trips once its presence outweighs its
 *     absence by T in all (duty > 50 % over a long run trips; < 50 % never).
 * The excursion tests (thresholds in the registers):
 *   voltage      supply > 0x3C high V or < 0x3C low V (a field of 0 = no
 *                limit on that side);
 *   temperature  trips at >= 0x3D trip degC; once tripped the excursion
 *                lasts while >= trip - hysteresis (released only below it);
 *   current      |current| > 0x3E mA;
 *   stall        |drive PWM| >= 0x3F PWM while the shaft stays within
 *                KM_PROTECT_STALL_WINDOW of where the excursion began
 *                (moving further restarts the timing: it is not stalled).
 *
 * Release (0x33 bit per protection): 0 = automatic, when the timer has
 * counted back down to 0 (the condition absent for T), or by a 0x36 clear;
 * 1 = only by a 0x36 clear. A clear of a protection whose excursion still
 * holds is refused (status bit 6) and changes nothing; a clear of one that
 * is not active is accepted and does nothing. Disabling a protection (0x32)
 * releases it at once and it is no longer watched.
 *
 * Action (0x34, 2 bits each): 00 free, 01 brake, 1x hold position — in
 * servo mode, for current and stall only; elsewhere 1x acts as brake.
 * Priority voltage > temperature > current > stall: the highest active
 * protection decides the action; every active one is reported. */
#ifndef KM_PROTECT_H
#define KM_PROTECT_H

#include <stdbool.h>
#include <stdint.h>

#include "km_live.h"
#include "km_params.h"
#include "km_status.h"

#define KM_PROTECT_FIXED_TIME_US 3000000u /* voltage and temperature: 3 s (§5.2) */
#define KM_PROTECT_STALL_WINDOW 10        /* 0.1 deg: moving more is not a stall */

typedef enum {
    KM_PROT_ACT_NONE = 0, /* no protection active: control as usual */
    KM_PROT_ACT_FREE,
    KM_PROT_ACT_BRAKE,
    KM_PROT_ACT_HOLD, /* hold the position the shaft had at the trip */
} km_prot_action_t;

typedef enum {
    KM_PROT_NORMAL = 0,
    KM_PROT_PENDING,
    KM_PROT_TRIPPED,
} km_prot_state_t;

/* What the supervisor looks at each tick. */
typedef struct {
    int32_t voltage_mv;
    int32_t current_ma;      /* signed; its magnitude is compared */
    int32_t temperature_c10; /* 0.1 degC */
    int32_t position;        /* 0.1 deg, any frame (only its changes matter) */
    int32_t drive_pwm;       /* the PWM the bridge drives now, signed or not */
    bool servo_mode;         /* servo mode owns the bridge (hold allowed) */
} km_protect_in_t;

typedef struct {
    uint32_t timer_us[4]; /* up/down excursion timers, index = bit number */
    int32_t stall_anchor; /* where the current stall excursion began */
    bool stall_anchored;
    uint8_t active; /* tripped protections, 0x36 bits */
    uint8_t over;   /* excursions present at the last step */
    uint8_t timing; /* timers not at 0 (the step's fast path when none) */
} km_protect_t;

void km_protect_init(km_protect_t *s);

/* One tick: updates every enabled protection and returns the action the
 * output stage must take (NONE when nothing is active). Sets ev->tripped
 * and ev->released to what tripped and released at this step (the fault
 * log's events, km_live.h); leaves the other fields alone. */
km_prot_action_t km_protect_step(km_protect_t *s, const km_protect_in_t *in, const km_control_params_t *p,
                                 uint32_t dt_us, km_protect_events_t *ev);

/* 0x36 write: release the protections in `mask`. False (refused, nothing
 * changes) if any of them is active and its excursion still holds, as seen
 * at the last step. */
bool km_protect_clear(km_protect_t *s, uint8_t mask);

/* Active protections (0x36, status bits 0-3). */
static inline uint8_t km_protect_active(const km_protect_t *s)
{
    return s->active;
}

km_prot_state_t km_protect_state(const km_protect_t *s, uint8_t bit);

/* The detection time of protection `bit` under params p, us. */
uint32_t km_protect_detect_us(const km_control_params_t *p, uint8_t bit);

#endif
