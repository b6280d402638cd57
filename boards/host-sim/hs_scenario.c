/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: --scenario FILE, the text form of a plant scenario
 * (boards/sim-common/km_sim_scenario.h has the format), read once at start
 * (and again by the re-executed image after a restart: same arguments). A
 * malformed file stops the program with the line and the reason: a bench
 * script that silently did less than written would mislead. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hs_io.h"
#include "km_sim_board.h"

static km_scn_event_t s_events[KM_SCN_MAX_EVENTS];
static uint32_t s_count;

static const struct {
    const char *name;
    km_scn_key_t key;
    long lo, hi;
} s_keys[] = {
    {"supply_mv", KM_SCN_SUPPLY_MV, 0, 65535},      {"ambient_dc", KM_SCN_AMBIENT_DC, -2730, 3000},
    {"load_mnm", KM_SCN_LOAD_MNM, -100000, 100000}, {"faults", KM_SCN_FAULTS, 0, 7},
    {"temp_dc", KM_SCN_TEMP_DC, -400, 2000},
};

static bool prv_fail(const char *path, unsigned line, const char *why)
{
    fprintf(stderr, "host-sim: %s:%u: %s\n", path, line, why);
    return false;
}

static const char *prv_skip_blanks(const char *p)
{
    while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') {
        p++;
    }
    return p;
}

/* One line "T_MS KEY VALUE": 1 if well formed, -1 if blank, 0 otherwise.
 * strtoul/strtol, not sscanf: a number too large for its type is an error
 * here, not a silently clamped or undefined value. */
static int prv_parse(const char *text, unsigned long *t_ms, char *name, size_t name_size, long *value)
{
    const char *p = prv_skip_blanks(text);
    if (*p == '\0') {
        return -1;
    }
    char *end;
    errno = 0;
    *t_ms = strtoul(p, &end, 10);
    if (end == p || errno != 0 || *p == '-') {
        return 0;
    }
    p = prv_skip_blanks(end);
    size_t k = 0;
    while (p[k] != '\0' && p[k] != ' ' && p[k] != '\t' && p[k] != '\r' && p[k] != '\n') {
        k++;
    }
    if (k == 0u || k >= name_size) {
        return 0;
    }
    memcpy(name, p, k);
    name[k] = '\0';
    p = prv_skip_blanks(p + k);
    errno = 0;
    *value = strtol(p, &end, 0);
    if (end == p || errno != 0) {
        return 0;
    }
    return *prv_skip_blanks(end) == '\0' ? 1 : 0;
}

/* The key named `name` with `value` in its range: its index in s_keys, or
 * -1 with *why set. */
static int prv_key(const char *name, long value, const char **why)
{
    size_t k = 0;
    while (k < sizeof s_keys / sizeof s_keys[0] && strcmp(s_keys[k].name, name) != 0) {
        k++;
    }
    if (k == sizeof s_keys / sizeof s_keys[0]) {
        *why = "unknown key (supply_mv, ambient_dc, load_mnm, faults, temp_dc)";
        return -1;
    }
    if (value < s_keys[k].lo || value > s_keys[k].hi) {
        *why = "value out of range for its key";
        return -1;
    }
    return (int)k;
}

/* One parsed line as an event after the ones held: false (with the
 * reason) for an unknown key, a value out of its range, a time before the
 * last one, or one event too many. */
static bool prv_add(const char *path, unsigned line, unsigned long t_ms, const char *name, long value)
{
    const char *why = NULL;
    const int k = prv_key(name, value, &why);
    if (k < 0) {
        return prv_fail(path, line, why);
    }
    if (t_ms > UINT32_MAX || (s_count > 0 && t_ms < s_events[s_count - 1u].t_ms)) {
        return prv_fail(path, line, "times must not decrease");
    }
    if (s_count == KM_SCN_MAX_EVENTS) {
        return prv_fail(path, line, "more than 64 events");
    }
    s_events[s_count].t_ms = (uint32_t)t_ms;
    s_events[s_count].key = (uint32_t)s_keys[k].key;
    s_events[s_count].value = (int32_t)value;
    s_count++;
    return true;
}

bool hs_scenario_load(const char *path)
{
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        fprintf(stderr, "host-sim: cannot open scenario %s: %s\n", path, strerror(errno));
        return false;
    }
    char text[256];
    unsigned line = 0;
    bool ok = true;
    s_count = 0;
    while (ok && fgets(text, sizeof text, f) != NULL) {
        line++;
        char *hash = strchr(text, '#');
        if (hash != NULL) {
            *hash = '\0';
        }
        char name[32];
        unsigned long t_ms;
        long value;
        const int n = prv_parse(text, &t_ms, name, sizeof name, &value);
        if (n < 0) {
            continue; /* blank or comment */
        }
        ok = n == 0 ? prv_fail(path, line, "expected: T_MS KEY VALUE")
                    : prv_add(path, line, t_ms, name, value);
    }
    fclose(f);
    if (!ok) {
        s_count = 0;
    }
    return ok;
}

const km_scn_event_t *km_sim_board_scenario(uint32_t *n)
{
    *n = s_count;
    return s_count != 0u ? s_events : NULL;
}

/* "KEY VALUE" (a runtime injection, hs_inject.c): the scenario line's
 * format without its time, checked as a file's line is. */
bool hs_scenario_parse_now(const char *text, uint32_t *key, int32_t *value, const char **why)
{
    char line[160];
    if (strlen(text) + 3u > sizeof line) {
        *why = "longer than a scenario line";
        return false;
    }
    snprintf(line, sizeof line, "0 %s", text);
    char name[32];
    unsigned long t_ms;
    long v;
    if (prv_parse(line, &t_ms, name, sizeof name, &v) != 1) {
        *why = "expected: KEY VALUE";
        return false;
    }
    const int k = prv_key(name, v, why);
    if (k < 0) {
        return false;
    }
    *key = (uint32_t)s_keys[k].key;
    *value = (int32_t)v;
    return true;
}
