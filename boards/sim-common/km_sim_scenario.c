/* SPDX-License-Identifier: Apache-2.0 */
/* The scenario player (km_sim_scenario.h): events applied on the plant's
 * clock. */
#include "km_sim_scenario.h"

#define PRV_UNM_PER_MNM 1000

void km_scn_start(km_scn_player_t *pl, const km_scn_event_t *ev, uint32_t n)
{
    pl->ev = ev;
    pl->n = ev == 0 ? 0u : (n > KM_SCN_MAX_EVENTS ? KM_SCN_MAX_EVENTS : n);
    pl->next = 0;
}

void km_scn_play(km_scn_player_t *pl, km_plant_t *plant, km_plant_input_t *in)
{
    const uint32_t now = km_plant_time_ms(plant);
    while (pl->next < pl->n && pl->ev[pl->next].t_ms <= now) {
        const km_scn_event_t *e = &pl->ev[pl->next++];
        switch ((km_scn_key_t)e->key) {
        case KM_SCN_SUPPLY_MV:
            km_plant_set_supply_mv(plant, e->value);
            break;
        case KM_SCN_AMBIENT_DC:
            km_plant_set_ambient_dc(plant, (int16_t)(e->value < -2730  ? -2730
                                                     : e->value > 3000 ? 3000
                                                                       : e->value));
            break;
        case KM_SCN_LOAD_MNM: {
            const int32_t mnm = e->value < -100000 ? -100000 : e->value > 100000 ? 100000 : e->value;
            in->ext_torque_unm = mnm * PRV_UNM_PER_MNM;
            break;
        }
        case KM_SCN_FAULTS:
            km_plant_set_faults(plant, (uint32_t)e->value);
            break;
        case KM_SCN_TEMP_DC:
            km_plant_set_temp_dc(plant, e->value < -400 ? -400 : e->value > 2000 ? 2000 : e->value);
            break;
        default:
            break; /* unknown: skipped (the loaders reject it first) */
        }
    }
}
