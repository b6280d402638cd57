/* SPDX-License-Identifier: Apache-2.0 */
/* Output stage: the one place a bridge command is made (direction 0x11
 * bit 2, the PWM bound, the bridge mode). */
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

/* The bridge for `mode`; PWM clamped to +-pwm_limit, sensor's frame. */
km_bridge_t km_output_bridge(km_bridge_mode_t mode, int32_t pwm_user, int32_t pwm_limit, bool reverse);

/* |PWM| for 0x49 (0 unless driving). */
int32_t km_output_pwm_reported(const km_bridge_t *b);

#endif
