/* SPDX-License-Identifier: Apache-2.0 */
/* Multi-turn position from a single-turn absolute encoder (docs/protocol.md
 * §5.3 0x46, §6): counts the wraps, so it must see the shaft every half
 * turn; the count is RAM and starts in [0, 360.0) deg at boot. */
#ifndef KM_TURN_COUNTER_H
#define KM_TURN_COUNTER_H

#include <stdint.h>

typedef struct {
    int32_t turns;   /* whole turns since boot, + = positive direction */
    uint16_t last;   /* the last raw reading, 0 .. counts - 1 */
    uint16_t counts; /* raw counts per turn, >= 2 */
} km_turn_counter_t;

/* Starts counting at `raw` (turn 0); raw is taken modulo counts_per_turn. */
void km_turn_counter_init(km_turn_counter_t *t, uint16_t counts_per_turn, uint16_t raw);

/* Takes the next raw reading; returns the position, 0.1 deg (wraps at int32). */
int32_t km_turn_counter_update(km_turn_counter_t *t, uint16_t raw);

#endif
