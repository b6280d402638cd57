/* SPDX-License-Identifier: Apache-2.0 */
/* The realistic model behind km_plant.h (cfg->real != NULL): internal to
 * sim/plant, called by km_plant.c. */
#ifndef KM_PLANT_REAL_H
#define KM_PLANT_REAL_H

#include <stdbool.h>
#include <stdint.h>

#include "km_plant.h"

/* Derives the realistic gains and starts the model at rest where
 * km_plant_init left the ideal state; false if cfg->real is invalid. */
bool km_plant_init_real(km_plant_t *p);

/* Advances the realistic model by dt_us (km_plant_step's contract). */
void km_plant_step_real(km_plant_t *p, const km_plant_input_t *in, uint32_t dt_us);

/* Re-seats the model on pos_ddeg / pos_rem_ndeg / speed_mdps after a
 * teleport or a restored physics: gears relaxed (centred in the play),
 * both sides at that speed, sensors sampled again. */
void km_plant_real_place(km_plant_t *p);

/* Notes the sub-step's |current| for km_plant_step_peak_ma. */
void km_plant_note_peak(km_plant_t *p);

#endif /* KM_PLANT_REAL_H */
