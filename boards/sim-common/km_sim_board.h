/* SPDX-License-Identifier: Apache-2.0 */
/* Simulated boards: access to the plant behind the hal (for test hooks). */
#ifndef KM_SIM_BOARD_H
#define KM_SIM_BOARD_H

#include <stdbool.h>
#include <stdint.h>

#include "km_plant.h"
#include "km_sim_scenario.h"

km_plant_t *km_sim_board_plant(void);

/* The plant the board builds at its next power-on or restart: the
 * `realistic` configuration unless told otherwise (docs/plant.md; host-sim
 * --plant ideal, a QEMU image built with -DKM_QEMU_PLANT=ideal). The encoder
 * product takes it without pot and end stops. */
void km_sim_board_select_plant(const km_plant_config_t *cfg);

/* The shaft, its heat and the environment are physics, not MCU state: a
 * restart of the firmware leaves them as they are. Each simulated board
 * carries them across its restart (QEMU: .noinit RAM; host-sim: the
 * re-exec's environment) by providing these two:
 *   keep:   called after every plant step with the physics now;
 *   recall: at boot, what the last keep before this boot's restart held;
 *           false at power-on (a fresh plant at rest at 0). */
void km_sim_board_keep(const km_plant_physics_t *ph);
bool km_sim_board_recall(km_plant_physics_t *out);

/* The app on a simulated board: km_app_init(), then this emulated bus's
 * floors (km_app_set_bus_floors: each board's run-time options), then
 * km_app_poll() for ever. A restart runs the board's main() again, so
 * the floors are handed over at every start. */
_Noreturn void km_sim_board_run(uint32_t gap_floor_us, uint32_t slot_floor_us);

/* Provided by each simulated board: the scenario to play (km_sim_scenario.h),
 * NULL with *n = 0 when there is none. */
const km_scn_event_t *km_sim_board_scenario(uint32_t *n);

/* One scenario event (km_scn_key_t, value) applied to the plant now, as the
 * player applies a due one: a change made by hand while the servo runs
 * (host-sim --inject). */
void km_sim_board_inject(uint32_t key, int32_t value);

#endif
