/* SPDX-License-Identifier: Apache-2.0 */
/* Protection supervisor (docs/protocol.md §5.2, status bits 0-3 of §4):
 * voltage, temperature, current and stall, each NORMAL -> PENDING ->
 * TRIPPED on an up/down detection timer; release per 0x33, action per 0x34
 * (priority voltage > temperature > current > stall). The rules:
 * docs/protocol-decisions.md "Protections"; docs/control-design.md. */
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

/* One tick: the action to take (NONE when nothing is active); sets
 * ev->tripped and ev->released only. */
km_prot_action_t km_protect_step(km_protect_t *s, const km_protect_in_t *in, const km_control_params_t *p,
                                 uint32_t dt_us, km_protect_events_t *ev);

/* 0x36 write: release `mask`; false (nothing changes) while an excursion
 * of an active one holds. */
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
