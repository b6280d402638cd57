/* SPDX-License-Identifier: Apache-2.0 */
/* Scenarios on the simulated boards: the bench a customer would build
 * around a servo (supply, ambient temperature, a load on the horn, a
 * broken wire), played on the plant's clock so a protection can be
 * exercised through bytes on the bus. host-sim reads them from a text file
 * (--scenario FILE), QEMU from a table in RAM that sim/bus/servo-bus loads
 * (boards/qemu-microbit/README.md); both hand the same events to this
 * player. Text format, one event per line, times never decreasing:
 *     T_MS KEY VALUE        # comment
 *   supply_mv   open-circuit supply, mV
 *   ambient_dc  ambient temperature, 0.1 degC
 *   load_mnm    external torque on the output, mN*m (+ = positive direction)
 *   faults      plant faults, mask: 1 pot open, 2 motor open, 4 NTC open
 *   temp_dc     the winding's temperature now, 0.1 degC (a heat gun on the
 *               case: it then relaxes toward ambient, time constant ~75 s)
 * T_MS is the plant's time since power-on: a restart of the MCU does not
 * restart the scenario (the plant's clock goes on, km_plant.h). */
#ifndef KM_SIM_SCENARIO_H
#define KM_SIM_SCENARIO_H

#include <stdbool.h>
#include <stdint.h>

#include "km_plant.h"

typedef enum {
    KM_SCN_SUPPLY_MV = 1,
    KM_SCN_AMBIENT_DC = 2,
    KM_SCN_LOAD_MNM = 3,
    KM_SCN_FAULTS = 4,
    KM_SCN_TEMP_DC = 5,
} km_scn_key_t;

/* 12 bytes, little-endian words: also the QEMU table's layout. */
typedef struct {
    uint32_t t_ms;
    uint32_t key; /* km_scn_key_t */
    int32_t value;
} km_scn_event_t;

#define KM_SCN_MAX_EVENTS 64u

typedef struct {
    const km_scn_event_t *ev;
    uint32_t n;
    uint32_t next; /* the first event not yet applied */
} km_scn_player_t;

void km_scn_start(km_scn_player_t *pl, const km_scn_event_t *ev, uint32_t n);

/* Applies, in order, every event due at the plant's time: to the plant
 * (supply, ambient, faults) or to the input the board drives it with
 * (load). Events whose key is unknown are skipped. */
void km_scn_play(km_scn_player_t *pl, km_plant_t *plant, km_plant_input_t *in);

#endif
