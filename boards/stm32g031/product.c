/* The product this board is built as: a potentiometer servo with +-135 deg
 * travel on a 2S Li-ion supply, 20 kg.cm class. A servo maker changes these
 * numbers (and board_config.c's sensor calibration) for their model. */
#include "km_app.h"

/* Position-loop gains and profile limits: the defaults were tuned on the
 * simulated plant of this servo class (docs/tuning.md says how). */
static const km_control_gains_t s_gains = KM_CONTROL_GAINS_DEFAULT;

static const km_product_t s_product = {
    .model = "KM-G031-P135",
    /* 0x@@##&&&&: no bootloader, hardware v1.0, software v0.1.00 */
    .firmware_version = 0x00100100u,
    .variant = KM_VARIANT_POTENTIOMETER,
    .max_current_ma = 2000,
    .max_speed_dps = 360,
    .zero_offset1 = 0,            /* factory calibration: set per unit at end of line */
    .angle_min = -1350,
    .angle_max = 1350,
    .voltage_high_v = 9,
    .voltage_low_v = 6,
    .current_threshold_ma = 1500,
    .baud_min_100 = 96,           /* USART1 at 64 MHz: 9600 .. 1 Mbaud within 2 % */
    .baud_max_100 = 10000,
    .current_max_ma = 3000,
    .speed_max_dps = 720,
    .travel_min = -1350,
    .travel_max = 1350,
    .zero_offset2_max = 100,
    .voltage_max_v = 20,
    .gains = &s_gains,
};

const km_product_t *km_board_product(void)
{
    return &s_product;
}
