/* SPDX-License-Identifier: Apache-2.0 */
/* The product this board is built as: a potentiometer servo with +-135 deg
 * travel on a 2S Li-ion supply, 20 kg.cm class. A servo maker changes these
 * numbers (and board_config.c's sensor calibration) for their model. */
#include "km_app.h"

#ifdef KM_APP_BOOTLOADER
#include "boot_layout.h"
#include "km_boot_board.h"
#endif

#ifndef KM_APP_SW_VERSION
#define KM_APP_SW_VERSION 0x0100u
#endif

/* Position-loop gains and profile limits: the defaults were tuned on the
 * simulated plant of this servo class (docs/tuning.md says how). */
static const km_control_gains_t s_gains = KM_CONTROL_GAINS_DEFAULT;

static const km_product_t s_product = {
    .model = "KM-G031-P135",
    /* 0x@@##&&&&: no bootloader, hardware v1.0, software v0.1.00 (a
     * second build for the update tests sets KM_APP_SW_VERSION) */
    .firmware_version = 0x00100000u | (uint32_t)(KM_APP_SW_VERSION),
    .variant = KM_PRODUCT_VARIANT, /* board.cmake: one variant, fixed at compile time */
    .max_current_ma = 2000,
    .max_speed_dps = 360,
    .zero_offset1 = 0, /* factory calibration: set per unit at end of line */
    .angle_min = -1350,
    .angle_max = 1350,
    .voltage_high_v = 9,
    .voltage_low_v = 6,
    .current_threshold_ma = 1500,
    .baud_min_100 = 96, /* USART1 at 64 MHz: 9600 .. 1 Mbaud within 2 % */
    .baud_max_100 = 10000,
    .current_max_ma = 3000,
    .speed_max_dps = 360,
    .travel_min = -1350,
    .travel_max = 1350,
    /* What a sound pot can read on this mechanics: the end stops must sit
     * inside. board_config.c's calibration puts the ADC rails at about
     * +-150.0 deg and sensors.c flags a reading within 16 counts of a
     * rail (beyond +-148.8 deg) as an open wiper; a servo maker sets these
     * from their stops. */
    .pos_read_min = -1480,
    .pos_read_max = 1480,
    .zero_offset2_max = 100,
    .voltage_max_v = 20,
    .gains = &s_gains,
};

const km_product_t *km_board_product(void)
{
#ifdef KM_APP_BOOTLOADER
    /* 0x0C's bootloader byte: the version the bootloader that started this
     * image left in the shared RAM words (docs/update.md §10). */
    static km_product_t s_with_boot;
    const volatile km_boot_shared_t *sh = (const volatile km_boot_shared_t *)BOOT_SHARED_ADDR;
    s_with_boot = s_product;
    if (sh->check == ~sh->boot_version && sh->boot_version <= 0xFFu) {
        s_with_boot.firmware_version |= sh->boot_version << 24;
    }
    return &s_with_boot;
#else
    return &s_product;
#endif
}
