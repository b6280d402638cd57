/* The product the simulated boards emulate: a potentiometer servo with
 * +-135 deg travel on a 2S Li-ion supply (7.4 V), matching the plant's
 * default parameters (sim/plant/km_plant_default.c). */
#include "km_app.h"

/* Position-loop gains and profile limits: the defaults were tuned on the
 * simulated plant of this servo class (docs/tuning.md says how). */
static const km_control_gains_t s_gains = KM_CONTROL_GAINS_DEFAULT;

static const km_product_t s_product = {
    .model = "KM-SIM-P135",
    /* 0x@@##&&&&: no bootloader, hardware v1.0, software v0.1.00 */
    .firmware_version = 0x00100100u,
    .variant = KM_VARIANT_POTENTIOMETER,
    .max_current_ma = 2000,       /* below the plant's 2.5 A stall current */
    .max_speed_dps = 360,         /* about the plant's no-load speed */
    .zero_offset1 = 0,
    .angle_min = -1350,
    .angle_max = 1350,
    .voltage_high_v = 9,          /* 2S: 8.4 V full, 6.0 V empty */
    .voltage_low_v = 6,
    .current_threshold_ma = 1500,
    .baud_min_100 = 96,           /* 9600 */
    .baud_max_100 = 10000,        /* 1 Mbaud */
    .current_max_ma = 3000,
    .speed_max_dps = 720,
    .travel_min = -1350,
    .travel_max = 1350,
    .zero_offset2_max = 100,      /* +-10 deg: more skews a pot's two sides */
    .voltage_max_v = 20,
    .gains = &s_gains,
};

const km_product_t *km_board_product(void)
{
    return &s_product;
}
