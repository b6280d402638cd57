/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: --inject PATH, scenario events at run time (hs_io.h): the bench
 * a user changes by hand (a supply sag, a heat gun, a load) while the servo
 * runs, as sim/bus/servo-bus --inject-dir and kmx web offer it
 * (docs/web.md "Bench"). The socket is bound again by every image: a
 * restart closes it (close-on-exec) and the next image replaces it. Its
 * name keeps the ID the servo was launched with; the datagram "id" asks
 * the ID it answers at now, which kmx.bench resolves an ID by. */
#define _GNU_SOURCE /* SOCK_NONBLOCK, SOCK_CLOEXEC */
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "hs_io.h"
#include "km_app.h"
#include "km_servo.h"
#include "km_sim_board.h"

static int s_inject_fd = -1;

/* Binds the datagram socket at path (replacing a stale one). */
bool hs_inject_open(const char *path)
{
    struct sockaddr_un addr;
    memset(&addr, 0, sizeof addr);
    addr.sun_family = AF_UNIX;
    const size_t len = strlen(path);
    if (len == 0u || len >= sizeof addr.sun_path) {
        fprintf(stderr, "host-sim: --inject %s: a socket path of 1..%zu bytes\n", path,
                sizeof addr.sun_path - 1u);
        return false;
    }
    memcpy(addr.sun_path, path, len + 1u);
    const int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        fprintf(stderr, "host-sim: --inject: no socket: %s\n", strerror(errno));
        return false;
    }
    (void)unlink(path); /* the previous image's, after a restart */
    if (bind(fd, (const struct sockaddr *)&addr, sizeof addr) != 0) {
        fprintf(stderr, "host-sim: --inject %s: %s\n", path, strerror(errno));
        close(fd);
        return false;
    }
    s_inject_fd = fd;
    return true;
}

/* The socket to poll (-1 without --inject). */
int hs_inject_poll_fd(void)
{
    return s_inject_fd;
}

/* The answer to one datagram's text: "ok id N" to "id" (0x0F in force), else
 * the event applied to the plant ("ok KEY VALUE") or why not ("error: ..."). */
static void prv_answer(const char *text, char *answer, size_t size)
{
    uint32_t key = 0;
    int32_t value = 0;
    const char *why = "longer than a scenario line";
    if (strcmp(text, "id") == 0) {
        snprintf(answer, size, "ok id %u", (unsigned)km_servo_id(km_app_servo()));
    } else if (hs_scenario_parse_now(text, &key, &value, &why)) {
        km_sim_board_inject(key, value);
        snprintf(answer, size, "ok %s", text);
        fprintf(stderr, "host-sim: injected %s\n", text);
    } else {
        snprintf(answer, size, "error: %s", why);
    }
}

/* One datagram: its answer (prv_answer) to a bound sender. */
void hs_inject_on_readable(void)
{
    char text[128];
    struct sockaddr_un from;
    socklen_t from_len = sizeof from;
    const ssize_t got =
        recvfrom(s_inject_fd, text, sizeof text - 1u, MSG_TRUNC, (struct sockaddr *)&from, &from_len);
    if (got < 0) {
        return;
    }
    char answer[160];
    if ((size_t)got < sizeof text) {
        text[got] = '\0';
        text[strcspn(text, "\r\n")] = '\0';
        prv_answer(text, answer, sizeof answer);
    } else {
        snprintf(answer, sizeof answer, "error: longer than a scenario line");
    }
    if (from_len > sizeof(sa_family_t)) { /* a bound sender: it waits for the answer */
        (void)sendto(s_inject_fd, answer, strlen(answer), MSG_DONTWAIT, (const struct sockaddr *)&from,
                     from_len);
    }
}
