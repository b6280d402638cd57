/* SPDX-License-Identifier: Apache-2.0 */
/* Default calibration: 270° pot, 50 mΩ shunt x 20 (1 V/A), 100k/10k divider,
 * 10 kΩ B3950 NTC under 10 kΩ to VDDA. */
#include "board_config.h"

const km_board_config_t km_board_config = {
    .pot_raw_min = 205u, /* 5 % of range */
    .pot_raw_max = 3890u,
    .rail_margin = 16u,
    .vref_mv = 3300u,
    .shunt_mohm = 50u,
    .shunt_gain = 20u,
    .shunt_offset_raw = 0u,
    .vdiv_num = 11u,
    .vdiv_den = 1u,
    /* raw = 4095 * R(T) / (R(T) + 10k), R(T) = 10k * exp(3950 (1/T - 1/298.15)) */
    .ntc_raw = {3996u, 3900u, 3740u, 3495u, 3156u, 2738u, 2278u, 1825u, 1419u, 1081u,
                815u,  613u,  462u,  350u,  267u,  206u,  160u,  126u,  100u,  80u},
    .ntc_first_c10 = -400,
    .ntc_step_c10 = 100,
};
