/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: the simulated plant's physics across a restart (km_sim_board.h).
 * A restart re-executes the program, so the last physics kept are handed to
 * the next image in the environment (KM_HS_PLANT), as the reset cause and
 * the bus descriptors are; a process started by hand has no such variable
 * and starts a fresh plant (a power-on). The plant's clock is kept too
 * (km_plant.h): a bench scenario runs on it, and a restart must not play
 * it again from its start. */
#define _GNU_SOURCE /* setenv, unsetenv */
#include <errno.h>
#include <inttypes.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hs_io.h"
#include "km_sim_board.h"

#define PRV_PLANT_ENV "KM_HS_PLANT"

static km_plant_physics_t s_kept;
static bool s_have;

void km_sim_board_keep(const km_plant_physics_t *ph)
{
    s_kept = *ph;
    s_have = true;
}

void hs_plant_prepare_exec(void)
{
    if (!s_have) {
        return;
    }
    char buf[176];
    snprintf(buf, sizeof buf,
             "%" PRId32 " %" PRId32 " %" PRId32 " %" PRId32 " %" PRId32 " %" PRId32 " %" PRIu32 " %" PRIu32,
             s_kept.pos_ddeg, s_kept.pos_rem_ndeg, s_kept.speed_mdps, s_kept.temp_uc, s_kept.supply_mv,
             s_kept.ambient_uc, s_kept.faults, s_kept.time_ms);
    setenv(PRV_PLANT_ENV, buf, 1);
}

bool km_sim_board_recall(km_plant_physics_t *out)
{
    const char *v = getenv(PRV_PLANT_ENV);
    if (v == NULL) {
        return false;
    }
    /* strtol, not sscanf: a field out of its type's range is malformed
     * here, not a silently clamped or undefined value. */
    int64_t f[8];
    const char *p = v;
    int n = 0;
    for (; n < 8; n++) {
        char *end;
        errno = 0;
        const long long x = strtoll(p, &end, 10);
        const bool is_unsigned = (n >= 6); /* faults, time_ms */
        if (end == p || errno != 0 || x < (is_unsigned ? 0 : INT32_MIN) ||
            x > (is_unsigned ? (long long)UINT32_MAX : INT32_MAX)) {
            break;
        }
        f[n] = x;
        p = end;
    }
    km_plant_physics_t ph;
    memset(&ph, 0, sizeof ph);
    if (n == 8) {
        ph.pos_ddeg = (int32_t)f[0];
        ph.pos_rem_ndeg = (int32_t)f[1];
        ph.speed_mdps = (int32_t)f[2];
        ph.temp_uc = (int32_t)f[3];
        ph.supply_mv = (int32_t)f[4];
        ph.ambient_uc = (int32_t)f[5];
        ph.faults = (uint32_t)f[6];
        ph.time_ms = (uint32_t)f[7];
    }
    unsetenv(PRV_PLANT_ENV); /* nothing started from here inherits it */
    if (n != 8) {
        fprintf(stderr, "host-sim: ignoring a malformed %s: a fresh plant\n", PRV_PLANT_ENV);
        return false;
    }
    *out = ph;
    return true;
}
