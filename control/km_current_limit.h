/* SPDX-License-Identifier: Apache-2.0 */
/* Current limit (docs/protocol.md §5.4 0x5C, bounded by §5.1 0x14): a PWM cap
 * that closes while the measured current is above the limit and opens
 * again below it, so the bridge never holds more than the limit for long
 * whatever the load (stall, a heavy inertia accelerated hard, low winding
 * resistance when cold). Integral action on the cap, per tick:
 *     cap += (limit - |I|) / KM_CURRENT_LIMIT_DIV   (PWM, clamped 0..1000)
 * On the simulated plant (2.5 mA of stall current per PWM) one tick's loop
 * gain is 2.5 / 8 = 0.31: settles in a few ms without ringing. A limit of
 * 0 means none (a product that does not sense current). */
#ifndef KM_CURRENT_LIMIT_H
#define KM_CURRENT_LIMIT_H

#include <stdint.h>

#define KM_CURRENT_LIMIT_DIV 8
#define KM_CURRENT_LIMIT_OPEN 1000 /* the cap when the limit is not acting */

typedef struct {
    int32_t cap; /* PWM the output may use now, 0..1000 */
} km_current_limit_t;

void km_current_limit_init(km_current_limit_t *l);

/* One tick: the measured current (mA, either sign) against `limit_ma`;
 * returns the PWM cap for this tick's output. */
int32_t km_current_limit_step(km_current_limit_t *l, int32_t current_ma, uint32_t limit_ma);

#endif
