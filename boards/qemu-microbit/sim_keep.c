/* SPDX-License-Identifier: Apache-2.0 */
/* The simulated plant's physics across a restart of the emulated MCU
 * (km_sim_board.h): QEMU keeps RAM across a SYSRESETREQ, so the physics
 * are copied into .noinit at every sensor read and taken back at the next
 * boot. A fresh QEMU starts with zeroed RAM: no valid copy, a power-on.
 * Servo images only (the plant lives there). */
#include <string.h>

#include "km_sim_board.h"

#define PRV_KEEP_MAGIC 0x504C4E54u /* "PLNT" */

typedef struct {
    uint32_t magic;
    km_plant_physics_t physics;
    uint32_t check; /* a sum over the physics: a half-written copy is refused */
} prv_keep_t;

static prv_keep_t s_keep __attribute__((section(".noinit")));

static uint32_t prv_check(const km_plant_physics_t *ph)
{
    const uint32_t *w = (const uint32_t *)(const void *)ph;
    uint32_t sum = PRV_KEEP_MAGIC;
    for (size_t i = 0; i < sizeof *ph / sizeof *w; i++) {
        sum = (sum << 5 | sum >> 27) ^ w[i];
    }
    return ~sum;
}

void km_sim_board_keep(const km_plant_physics_t *ph)
{
    s_keep.magic = 0u; /* a reset in the middle of the copy leaves no valid one */
    s_keep.physics = *ph;
    s_keep.check = prv_check(ph);
    s_keep.magic = PRV_KEEP_MAGIC;
}

bool km_sim_board_recall(km_plant_physics_t *out)
{
    const bool ok = s_keep.magic == PRV_KEEP_MAGIC && s_keep.check == prv_check(&s_keep.physics);
    s_keep.magic = 0u;
    if (ok) {
        *out = s_keep.physics;
    }
    return ok;
}
