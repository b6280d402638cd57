/* SPDX-License-Identifier: Apache-2.0 */
/* Template: the product this board is built as (km_product.h): the model
 * name, versions and the limits the protocol's registers start from. A
 * servo maker sets these for their model. */
#include "km_app.h"

/* Position-loop gains and profile limits: tune them on your servo's plant
 * (docs/tuning.md). */
static const km_control_gains_t s_gains = KM_CONTROL_GAINS_DEFAULT;

static const km_product_t s_product = {
    .model = "KM-TEMPLATE",
    /* 0x@@##&&&&: no bootloader, hardware v1.0, software v0.1.00 */
    .firmware_version = 0x00100100u,
    .variant = KM_VARIANT_POTENTIOMETER,
    .max_current_ma = 2000,
    .max_speed_dps = 360,
    .zero_offset1 = 0,
    .angle_min = -1350,
    .angle_max = 1350,
    .voltage_high_v = 9,
    .voltage_low_v = 6,
    .current_threshold_ma = 1500,
    .baud_min_100 = 96, /* what uart.c can make within 2 % */
    .baud_max_100 = 10000,
    .current_max_ma = 3000,
    .speed_max_dps = 360,
    .travel_min = -1350,
    .travel_max = 1350,
    .pos_read_min = -1480, /* what a sound position sensor can read */
    .pos_read_max = 1480,
    .zero_offset2_max = 100,
    .voltage_max_v = 20,
    .gains = &s_gains,
};

/* The product the app runs (km_app.h). */
const km_product_t *km_board_product(void)
{
    return &s_product;
}
