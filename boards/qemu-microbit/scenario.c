/* SPDX-License-Identifier: Apache-2.0 */
/* QEMU: the plant scenario (km_sim_scenario.h) as a table in RAM at 0x20000040,
 * written by QEMU's -device loader (docs/architecture.md "qemu-microbit's scenario table"). */
#include <stddef.h>

#include "km_sim_board.h"

#define PRV_SCENARIO_MAGIC 0x4B4D5343u

typedef struct {
    uint32_t magic;
    uint32_t count;
    km_scn_event_t ev[KM_SCN_MAX_EVENTS];
} prv_table_t;

__attribute__((section(".km_scenario"), used)) static volatile prv_table_t s_table;
static km_scn_event_t s_events[KM_SCN_MAX_EVENTS];

const km_scn_event_t *km_sim_board_scenario(uint32_t *n)
{
    *n = 0;
    if (s_table.magic != PRV_SCENARIO_MAGIC) {
        return NULL;
    }
    const uint32_t count = s_table.count > KM_SCN_MAX_EVENTS ? KM_SCN_MAX_EVENTS : s_table.count;
    for (uint32_t i = 0; i < count; i++) {
        s_events[i].t_ms = s_table.ev[i].t_ms;
        s_events[i].key = s_table.ev[i].key;
        s_events[i].value = s_table.ev[i].value;
    }
    *n = count;
    return count != 0u ? s_events : NULL;
}
