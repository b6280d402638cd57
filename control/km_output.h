/* SPDX-License-Identifier: Apache-2.0 */
/* Output stage: the one place a bridge command is made. Applies the
 * direction bit (0x11 bit 2: the loop works in the master's frame, the
 * motor turns the sensor's way), the PWM limit (0x5B, and a move's own
 * cap from 0x67 low nibble 2), and the bridge mode (free, brake, PWM). */
#ifndef KM_OUTPUT_H
#define KM_OUTPUT_H

#include <stdbool.h>
#include <stdint.h>

typedef enum {
    KM_BRIDGE_FREE = 0,
    KM_BRIDGE_BRAKE = 1,
    KM_BRIDGE_PWM = 2,
} km_bridge_mode_t;

typedef struct {
    km_bridge_mode_t mode;
    int16_t pwm; /* -1000..1000 when mode is PWM, sensor frame */
} km_bridge_t;

/* The bridge for `mode`; with PWM, `pwm_user` (master's frame) is clamped
 * to +-pwm_limit and turned into the sensor's frame when `reverse`. */
km_bridge_t km_output_bridge(km_bridge_mode_t mode, int32_t pwm_user, int32_t pwm_limit, bool reverse);

/* |PWM| for 0x49 (0 unless driving). */
int32_t km_output_pwm_reported(const km_bridge_t *b);

#endif
