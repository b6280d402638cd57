/* SPDX-License-Identifier: Apache-2.0 */
/* The products the simulated boards emulate, on a 2S Li-ion supply (7.4 V)
 * and the plant's default motor (sim/plant/km_plant_default.c):
 *  - "KM-SIM-P135", the default: a potentiometer servo, +-135 deg travel;
 *  - "KM-SIM-ENCODER": a multi-turn encoder servo (0x6F, 0x70 turns), travel
 *    +-3200.0 deg, no angle limits, on a plant without end stops or pot
 *    (km_sim_board.c). Chosen before the app starts with
 *    km_sim_product_select(): host-sim --product, the QEMU option word. */
#include "km_app.h"
#include "km_sim_product.h"

#ifdef KM_APP_BOOTLOADER
#include "boot_layout.h"
#include "km_boot_board.h"
#endif

/* The software field of 0x0C (0x0100 = v0.1.00); the update tests build a
 * second image with another (docs/update.md). */
#ifndef KM_APP_SW_VERSION
#define KM_APP_SW_VERSION 0x0100u
#endif
#define PRV_FW_VERSION (0x00100000u | (uint32_t)(KM_APP_SW_VERSION))

/* Position-loop gains and profile limits: the defaults were tuned on the
 * simulated plant of this servo class (docs/tuning.md says how). */
static const km_control_gains_t s_gains = KM_CONTROL_GAINS_DEFAULT;

static const km_product_t s_product = {
    .model = "KM-SIM-P135",
    /* 0x@@##&&&&: bootloader (0 = none, else set at run time below),
     * hardware v1.0, software v0.1.00 */
    .firmware_version = PRV_FW_VERSION,
    .variant = KM_VARIANT_POTENTIOMETER,
    .max_current_ma = 2000, /* below the plant's 2.5 A stall current */
    .max_speed_dps = 360,   /* about the plant's no-load speed */
    .zero_offset1 = 0,
    .angle_min = -1350,
    .angle_max = 1350,
    .voltage_high_v = 9, /* 2S: 8.4 V full, 6.0 V empty */
    .voltage_low_v = 6,
    .current_threshold_ma = 1500,
    .baud_min_100 = 96,    /* 9600 */
    .baud_max_100 = 10000, /* 1 Mbaud */
    .current_max_ma = 3000,
    .speed_max_dps = 360,
    .travel_min = -1350,
    .travel_max = 1350,
    /* the plant's stops at +-150.0 deg and 7.5 deg of tolerance; its pot
     * reads +-165.0 deg at the rails (sim/plant/km_plant_default.c) */
    .pos_read_min = -1575,
    .pos_read_max = 1575,
    .zero_offset2_max = 100, /* +-10 deg: more skews a pot's two sides */
    .voltage_max_v = 20,
    .gains = &s_gains,
};

/* Same motor, gearbox and supply as the pot product, so the same gains and
 * speed/current figures; what differs is the variant (§6) and the limits. */
static const km_product_t s_product_encoder = {
    .model = "KM-SIM-ENCODER",
    .firmware_version = PRV_FW_VERSION,
    .variant = KM_VARIANT_ENCODER,
    .max_current_ma = 2000,
    .max_speed_dps = 360,
    .zero_offset1 = 0,
    .angle_min = 0, /* 0 = no angle limit (multi-turn) */
    .angle_max = 0,
    .voltage_high_v = 9,
    .voltage_low_v = 6,
    .current_threshold_ma = 1500,
    .baud_min_100 = 96,
    .baud_max_100 = 10000,
    .current_max_ma = 3000,
    .speed_max_dps = 360,
    .travel_min = -32000, /* +-3200.0 deg: the widest 0x19/0x1A carry (i16) */
    .travel_max = 32000,
    .zero_offset2_max = 1800, /* +-180 deg: an encoder's zero can be anywhere */
    .voltage_max_v = 20,
    .gains = &s_gains,
};

static km_sim_variant_t s_selected = KM_SIM_PRODUCT_POT;

void km_sim_product_select(km_sim_variant_t which)
{
    s_selected = which;
}

const km_product_t *km_board_product(void)
{
    const km_product_t *p = s_selected == KM_SIM_PRODUCT_ENCODER ? &s_product_encoder : &s_product;
#ifdef KM_APP_BOOTLOADER
    /* 0x0C's bootloader byte: the version the bootloader that started
     * this image left in the shared RAM words (docs/update.md §10). */
    static km_product_t s_with_boot;
    const volatile km_boot_shared_t *sh = (const volatile km_boot_shared_t *)BOOT_SHARED_ADDR;
    s_with_boot = *p;
    if (sh->check == ~sh->boot_version && sh->boot_version <= 0xFFu) {
        s_with_boot.firmware_version |= sh->boot_version << 24;
    }
    return &s_with_boot;
#else
    return p;
#endif
}
