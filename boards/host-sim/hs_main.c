/* host-sim: the firmware as a native Linux program (software in the loop).
 *   km-servo-host-sim --listen 127.0.0.1:7001 --flash servo1.flash
 *   km-servo-host-sim --pty --flash servo1.flash
 * The bus is a TCP socket (one client at a time) or a pseudo-terminal; the
 * user-data flash is a file with NOR rules; sensors read the simulated plant. */
#include <stdio.h>
#include <string.h>

#include "hs_flash.h"
#include "hs_io.h"
#include "km_app.h"

void hs_system_set_argv(char **argv);
void hs_board_set_flash(const km_flash_t *flash);

static int prv_usage(const char *argv0)
{
    fprintf(stderr, "usage: %s (--listen HOST:PORT | --pty) --flash FILE [--baud N]\n", argv0);
    return 2;
}

int main(int argc, char **argv)
{
    const char *listen_at = NULL;
    const char *flash_path = NULL;
    int use_pty = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--listen") == 0 && i + 1 < argc) {
            listen_at = argv[++i];
        } else if (strcmp(argv[i], "--flash") == 0 && i + 1 < argc) {
            flash_path = argv[++i];
        } else if (strcmp(argv[i], "--baud") == 0 && i + 1 < argc) {
            i++; /* bytes over TCP have no line rate; the stored 0x10 is what the servo reports */
        } else if (strcmp(argv[i], "--pty") == 0) {
            use_pty = 1;
        } else {
            return prv_usage(argv[0]);
        }
    }
    if (!flash_path || (!listen_at && !use_pty)) {
        return prv_usage(argv[0]);
    }
    hs_system_set_argv(argv);
    km_flash_t flash;
    if (!hs_flash_open(flash_path, &flash)) {
        return 1;
    }
    hs_board_set_flash(&flash);
    if (!hs_uart_adopt()) {
        if (use_pty ? !hs_uart_open_pty() : !hs_uart_open_tcp(listen_at)) {
            return 1;
        }
    }
    km_app_run();
}
