/* SPDX-License-Identifier: Apache-2.0 */
/* Multi-turn position from a single-turn absolute encoder (encoder
 * products): the sensor gives the shaft's angle within one turn as raw
 * counts; this counts the wraps, so it must see the shaft at least every
 * half turn (at the 1 kHz tick: below 180,000 deg/s). Pure, fixed-point,
 * no division by a variable on the update path but the one that scales
 * counts to 0.1 deg.
 *
 * The turn count is RAM: at boot (power-on or restart) it starts from the
 * angle within one turn, [0, 360.0) deg, as on an encoder servo without a
 * battery-backed turn counter. docs/protocol.md §5.3 0x46, §6. */
#ifndef KM_TURN_COUNTER_H
#define KM_TURN_COUNTER_H

#include <stdint.h>

typedef struct {
    int32_t turns;   /* whole turns since boot, + = positive direction */
    uint16_t last;   /* the last raw reading, 0 .. counts - 1 */
    uint16_t counts; /* raw counts per turn, >= 2 */
} km_turn_counter_t;

/* Starts counting at `raw` (turn 0). `counts_per_turn` >= 2; a raw value
 * at or above it is taken modulo it. */
void km_turn_counter_init(km_turn_counter_t *t, uint16_t counts_per_turn, uint16_t raw);

/* Takes the next raw reading; returns the multi-turn position, 0.1 deg
 * (raw scaled to the nearest 0.1 deg; wraps at int32 like 0x46's i32). */
int32_t km_turn_counter_update(km_turn_counter_t *t, uint16_t raw);

#endif
