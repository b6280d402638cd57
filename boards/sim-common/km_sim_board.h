/* Simulated boards: access to the plant behind the hal (for test hooks). */
#ifndef KM_SIM_BOARD_H
#define KM_SIM_BOARD_H

#include "km_plant.h"

km_plant_t *km_sim_board_plant(void);

#endif
