/* The firmware application, the same on every board: hal -> receive queue ->
 * parser -> dispatcher -> answer timer -> hal; the user-data store; the fixed
 * control tick. A board's main() prepares its hal and calls km_app_run(). */
#ifndef KM_APP_H
#define KM_APP_H

#include "km_hal_flash.h"
#include "km_product.h"

/* Provided by the board: its product config and its user-data flash region. */
const km_product_t *km_board_product(void);
const km_flash_t *km_board_flash(void);

/* Measurement hook (weak, empty by default): see km_app.c. */
void km_app_answer_started(uint32_t frame_end, uint32_t started, uint32_t delay_us);

/* Initialises everything and runs the main loop; never returns. */
_Noreturn void km_app_run(void);

#endif
