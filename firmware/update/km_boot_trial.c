/* SPDX-License-Identifier: Apache-2.0 */
/* The trial of a new image (km_boot_trial.h, docs/update.md §3a). */
#include "km_boot_trial.h"

#include "km_frame.h"

uint32_t km_boot_attempts(const volatile km_boot_shared_t *sh)
{
    const uint32_t n = sh->attempts;
    const bool counted = sh->attempts_check == (n ^ KM_BOOT_TRIAL_KEY) && n <= KM_BOOT_TRIAL_MAX;
    return counted ? n : 0u;
}

/* Stores a count with its check word. */
static void prv_set_attempts(volatile km_boot_shared_t *sh, uint32_t n)
{
    sh->attempts = n;
    sh->attempts_check = n ^ KM_BOOT_TRIAL_KEY;
}

km_boot_decision_t km_boot_decide(volatile km_boot_shared_t *sh, bool image_ok)
{
    uint32_t n = km_boot_attempts(sh);
    if (sh->confirmed == KM_BOOT_CONFIRMED_MAGIC) {
        n = 0u; /* the last start served the bus: a new trial */
    }
    const bool asked = sh->request == KM_BOOT_REQUEST_MAGIC;
    sh->confirmed = 0u;
    sh->request = 0u;
    sh->app_running = 0u;
    km_boot_decision_t d = KM_BOOT_RUN;
    if (!image_ok) {
        d = KM_BOOT_STAY_NO_IMAGE;
    } else if (asked) {
        d = KM_BOOT_STAY_ASKED;
    } else if (n >= KM_BOOT_TRIAL_MAX) {
        d = KM_BOOT_STAY_GAVE_UP;
    } else {
        n++;
    }
    prv_set_attempts(sh, n);
    return d;
}

void km_boot_trial_fresh(volatile km_boot_shared_t *sh)
{
    prv_set_attempts(sh, 0u);
}

bool km_boot_started_by_loader(const volatile km_boot_shared_t *sh)
{
    return sh->check == ~sh->boot_version;
}

void km_boot_confirm(volatile km_boot_shared_t *sh)
{
    sh->confirmed = KM_BOOT_CONFIRMED_MAGIC;
}

void km_boot_handoff_set(volatile km_boot_shared_t *sh, uint8_t id, uint32_t baud)
{
    sh->address = ((baud / 100u) << 16) | ((uint32_t)(uint8_t)~id << 8) | id;
}

bool km_boot_handoff_get(const volatile km_boot_shared_t *sh, uint8_t *id, uint32_t *baud)
{
    const uint32_t w = sh->address;
    const uint32_t lo = w & 0xFFu;
    *id = (uint8_t)lo;
    *baud = (w >> 16) * 100u;
    return ((w >> 8) & 0xFFu) == (lo ^ 0xFFu) && lo <= KM_ID_MAX && *baud - 9600u <= 1000000u - 9600u;
}
