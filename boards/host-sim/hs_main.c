/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: the firmware as a native Linux program (software in the loop).
 *   km-servo-host-sim --listen 127.0.0.1:7001 --flash servo1.flash
 *   km-servo-host-sim --pty --flash servo1.flash [--gap-floor-us 0] [--slot-floor-us N]
 *                     [--baud N] [--report-baud] [--product pot|encoder] [--plant realistic|ideal]
 *                     [--scenario FILE]
 * The options and what survives a restart: docs/architecture.md "host-sim's options". */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hs_flash.h"
#include "hs_io.h"
#include "km_app.h"
#include "km_sim_board.h"
#include "km_sim_product.h"

void hs_system_set_argv(char **argv);
void hs_board_set_flash(const km_flash_t *flash);

/* --gap-floor-us when not given: host scheduling stalls, not the real rule. */
#define HS_GAP_FLOOR_DEFAULT_US 20000u

/* The products' baud range (boards/sim-common/km_sim_product.c). */
#define HS_BAUD_MIN 9600u
#define HS_BAUD_MAX 1000000u

static int prv_usage(const char *argv0)
{
    fprintf(stderr,
            "usage: %s (--listen HOST:PORT | --pty) --flash FILE [--baud N] [--gap-floor-us N]\n"
            "          [--product pot|encoder] [--plant realistic|ideal] [--scenario FILE]\n"
            "          [--inject PATH]\n"
            "  --listen HOST:0   a port the kernel picks, printed \"port N\" on stdout\n"
            "  --gap-floor-us N  least silence inside a frame that drops it, in us, when it\n"
            "                    exceeds the parser's max(10 byte times, 1 ms); default %u\n"
            "                    (host scheduling stalls); 0 = the real rule\n"
            "  --slot-floor-us N least super-ID / 0x82 answer slot, in us; default 0 (the\n"
            "                    slot rule alone)\n"
            "  --product P       pot (default, KM-SIM-P135) or encoder (KM-SIM-ENCODER,\n"
            "                    multi-turn); a restart keeps it and the shaft where it\n"
            "                    is; the encoder then reads its angle within one turn\n"
            "  --plant NAME      the simulated plant (docs/plant.md): realistic (default:\n"
            "                    sensor noise, friction, backlash, a shared supply) or ideal\n"
            "                    (exact sensors; regression tests)\n"
            "  --scenario FILE   a bench scenario played on the plant's clock: lines\n"
            "                    T_MS KEY VALUE, keys supply_mv, ambient_dc (0.1 degC),\n"
            "                    load_mnm (mN*m), faults (1 pot, 2 motor, 4 NTC open),\n"
            "                    temp_dc (winding temperature now, 0.1 degC)\n"
            "  --inject PATH     a Unix datagram socket taking one \"KEY VALUE\" of the\n"
            "                    scenario keys per datagram, applied at once (answered\n"
            "                    \"ok ...\" or \"error: ...\" to a bound sender); \"id\" is\n"
            "                    answered \"ok id N\", the ID the servo answers at now\n"
            "  --baud N          the master's line rate on the wire, %u..%u; the servo runs at\n"
            "                    its stored 0x10 and hears garbage at another rate (default:\n"
            "                    the master follows the servo)\n"
            "  --report-baud     print \"baud N\" on stdout at every UART start (servo-bus)\n",
            argv0, HS_GAP_FLOOR_DEFAULT_US, HS_BAUD_MIN, HS_BAUD_MAX);
    return 2;
}

static int prv_parse_u32(const char *text, uint32_t *out)
{
    char *end = NULL;
    errno = 0;
    const unsigned long v = strtoul(text, &end, 10);
    if (errno != 0 || end == text || *end != '\0' || text[0] == '-' || v > UINT32_MAX) {
        return 0;
    }
    *out = (uint32_t)v;
    return 1;
}

/* --baud N: the master's line rate on the wire (0 = taken, else the exit code). */
static int prv_baud(const char *value)
{
    uint32_t baud;
    if (!prv_parse_u32(value, &baud) || baud < HS_BAUD_MIN || baud > HS_BAUD_MAX) {
        fprintf(stderr, "host-sim: --baud '%s': a baud rate is a whole number in %u..%u\n", value,
                HS_BAUD_MIN, HS_BAUD_MAX);
        return 2;
    }
    hs_uart_set_wire_baud(baud);
    return 0;
}

/* --product pot|encoder (0 = taken, else the exit code). */
static int prv_product(const char *value, const char *argv0)
{
    if (strcmp(value, "pot") == 0) {
        km_sim_product_select(KM_SIM_PRODUCT_POT);
    } else if (strcmp(value, "encoder") == 0) {
        km_sim_product_select(KM_SIM_PRODUCT_ENCODER);
    } else {
        return prv_usage(argv0);
    }
    return 0;
}

/* --plant realistic|ideal (0 = taken, else the exit code). */
static int prv_plant(const char *value, const char *argv0)
{
    const km_plant_config_t *cfg = km_plant_config_named(value);
    if (cfg == NULL) {
        return prv_usage(argv0);
    }
    km_sim_board_select_plant(cfg);
    return 0;
}

/* What the options say: where the bus and the flash are, and the bus
 * floors handed to the app. */
typedef struct {
    const char *listen_at;
    const char *flash_path;
    int use_pty;
    uint32_t gap_floor_us;
    uint32_t slot_floor_us;
} prv_args_t;

/* Option `name` with its `value`: 0 when taken, -1 when `name` is not an
 * option with a value, else the exit code of a bad value. */
static int prv_option(prv_args_t *a, const char *name, const char *value, const char *argv0)
{
    if (strcmp(name, "--listen") == 0) {
        a->listen_at = value;
        return 0;
    }
    if (strcmp(name, "--flash") == 0) {
        a->flash_path = value;
        return 0;
    }
    if (strcmp(name, "--baud") == 0) {
        return prv_baud(value);
    }
    if (strcmp(name, "--gap-floor-us") == 0) {
        return prv_parse_u32(value, &a->gap_floor_us) ? 0 : prv_usage(argv0);
    }
    if (strcmp(name, "--slot-floor-us") == 0) {
        return prv_parse_u32(value, &a->slot_floor_us) ? 0 : prv_usage(argv0);
    }
    if (strcmp(name, "--product") == 0) {
        return prv_product(value, argv0);
    }
    if (strcmp(name, "--scenario") == 0) {
        return hs_scenario_load(value) ? 0 : 2;
    }
    if (strcmp(name, "--plant") == 0) {
        return prv_plant(value, argv0);
    }
    if (strcmp(name, "--inject") == 0) {
        return hs_inject_open(value) ? 0 : 2;
    }
    return -1;
}

int main(int argc, char **argv)
{
    prv_args_t a = {NULL, NULL, 0, HS_GAP_FLOOR_DEFAULT_US, 0u};
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--report-baud") == 0) {
            hs_uart_set_report_baud(true);
        } else if (strcmp(argv[i], "--pty") == 0) {
            a.use_pty = 1;
        } else {
            const int r = i + 1 < argc ? prv_option(&a, argv[i], argv[i + 1], argv[0]) : -1;
            if (r != 0) {
                return r < 0 ? prv_usage(argv[0]) : r;
            }
            i++;
        }
    }
    if (!a.flash_path || (!a.listen_at && !a.use_pty)) {
        return prv_usage(argv[0]);
    }
    hs_system_set_argv(argv);
    km_flash_t flash;
    if (!hs_flash_open(a.flash_path, &flash)) {
        return 1;
    }
    hs_board_set_flash(&flash);
    if (!hs_uart_adopt()) {
        if (a.use_pty ? !hs_uart_open_pty() : !hs_uart_open_tcp(a.listen_at)) {
            return 1;
        }
    }
    km_sim_board_run(a.gap_floor_us, a.slot_floor_us);
}
