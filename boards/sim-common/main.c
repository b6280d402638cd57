/* Entry point of the simulated servo image (qemu-microbit): the application
 * is the same on every board; the product (pot or encoder) comes from the
 * run-time option word (boards/qemu-microbit/README.md). */
#include "km_app.h"
#include "km_board.h"
#include "km_sim_product.h"

int main(void)
{
    km_sim_product_select(km_board_option_product() == 1u ? KM_SIM_PRODUCT_ENCODER
                                                          : KM_SIM_PRODUCT_POT);
    km_app_run();
}
