/* SPDX-License-Identifier: Apache-2.0 */
/* Entry point of the simulated servo image (qemu-microbit): the application
 * is the same on every board; the product (pot or encoder) and the bus
 * floors come from the run-time option words (boards/qemu-microbit/README.md). */
#include "km_board.h"
#include "km_sim_board.h"
#include "km_sim_product.h"

int main(void)
{
    km_sim_product_select(km_board_option_product() == 1u ? KM_SIM_PRODUCT_ENCODER : KM_SIM_PRODUCT_POT);
    km_sim_board_run(km_board_option_gap_floor_us(), km_board_option_slot_floor_us());
}
