/* SPDX-License-Identifier: Apache-2.0 */
/* Current limit (docs/protocol.md §5.4 0x5C, bounded by §5.1 0x14): an
 * integral PWM cap, cap += (limit - |I|) / KM_CURRENT_LIMIT_DIV a tick,
 * 0..1000; a limit of 0 is none. docs/control-design.md. */
#ifndef KM_CURRENT_LIMIT_H
#define KM_CURRENT_LIMIT_H

#include <stdint.h>

#define KM_CURRENT_LIMIT_DIV 8
#define KM_CURRENT_LIMIT_OPEN 1000 /* the cap when the limit is not acting */

typedef struct {
    int32_t cap; /* PWM the output may use now, 0..1000 */
} km_current_limit_t;

void km_current_limit_init(km_current_limit_t *l);

/* One tick: returns the PWM cap for the measured current (mA, either sign). */
int32_t km_current_limit_step(km_current_limit_t *l, int32_t current_ma, uint32_t limit_ma);

#endif
