/* SPDX-License-Identifier: Apache-2.0 */
/* What the qemu-microbit board offers beyond the hal contracts: the store's
 * flash and the simulated plant's hook-up (docs/architecture.md "qemu-microbit's
 * plant hook-up"). */
#ifndef KM_BOARD_H
#define KM_BOARD_H

#include <stdint.h>

#include "km_hal_flash.h"
#include "km_hal_sensors.h"

/* The flash region of the user-data store (top pages, see the linker script). */
const km_flash_t *km_board_flash(void);

typedef enum {
    KM_BOARD_MOTOR_FREE = 0, /* coast: the state after init */
    KM_BOARD_MOTOR_DRIVE,
    KM_BOARD_MOTOR_BRAKE,
} km_board_motor_mode_t;

typedef struct {
    km_board_motor_mode_t mode;
    int16_t pwm; /* -1000..1000, meaningful in DRIVE */
} km_board_motor_cmd_t;

/* The last command given through km_hal_motor.h. */
km_board_motor_cmd_t km_board_motor_command(void);

/* The product option word at 0x20000008: 0 pot (also when unset), 1 encoder. */
uint32_t km_board_option_product(void);

/* The bus floors at 0x20000004 and 0x2000000C (default: 20 ms gap floor, no slot floor). */
uint32_t km_board_option_gap_floor_us(void);
uint32_t km_board_option_slot_floor_us(void);

/* Replace the readings km_hal_sensors_read() returns. */
void km_board_sensors_publish(const km_sensors_t *readings);

#endif
