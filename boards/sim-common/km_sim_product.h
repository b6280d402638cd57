/* SPDX-License-Identifier: Apache-2.0 */
/* Simulated boards: which product they emulate (km_sim_product.c). */
#ifndef KM_SIM_PRODUCT_H
#define KM_SIM_PRODUCT_H

typedef enum {
    KM_SIM_PRODUCT_POT = 0,     /* "KM-SIM-P135", potentiometer, +-135 deg (default) */
    KM_SIM_PRODUCT_ENCODER = 1, /* "KM-SIM-ENCODER", multi-turn, no end stops */
} km_sim_variant_t;

/* Select before km_app_run(): km_board_product() answers it, and the plant
 * is set up to match at sensor init (km_sim_board.c). */
void km_sim_product_select(km_sim_variant_t which);

#endif
