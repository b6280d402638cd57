/* host-sim: the servo bus over TCP (one client at a time; a new client may
 * connect after the old one leaves) or over a pseudo-terminal. Bytes the
 * client sends arrive as RX "interrupts"; answers are written back whole.
 * Like a real half-duplex transceiver, the servo does not hear its own TX. */
#define _GNU_SOURCE /* posix_openpt, ptsname */
#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "hs_io.h"
#include "km_hal_time.h"
#include "km_hal_uart.h"

static int s_listen_fd = -1;
static int s_conn_fd = -1;
static int s_pty_fd = -1;
static km_uart_rx_handler_t s_rx;
static void *s_rx_ctx;

/* A restart re-executes the program (hs_system.c); the bus must stay
 * connected across it, as a wire stays attached to a rebooting servo, so the
 * socket descriptors are handed to the new image through the environment. */
static int prv_env_fd(const char *name)
{
    const char *v = getenv(name);
    return v ? atoi(v) : -1;
}

void hs_uart_prepare_exec(void)
{
    char buf[16];
    snprintf(buf, sizeof buf, "%d", s_listen_fd);
    setenv("KM_HS_LISTEN_FD", buf, 1);
    snprintf(buf, sizeof buf, "%d", s_conn_fd);
    setenv("KM_HS_CONN_FD", buf, 1);
    snprintf(buf, sizeof buf, "%d", s_pty_fd);
    setenv("KM_HS_PTY_FD", buf, 1);
}

bool hs_uart_adopt(void)
{
    if (!getenv("KM_HS_LISTEN_FD")) {
        return false;
    }
    s_listen_fd = prv_env_fd("KM_HS_LISTEN_FD");
    s_conn_fd = prv_env_fd("KM_HS_CONN_FD");
    s_pty_fd = prv_env_fd("KM_HS_PTY_FD");
    return true;
}

bool hs_uart_open_tcp(const char *host_port)
{
    char host[128];
    const char *colon = strrchr(host_port, ':');
    if (!colon || (size_t)(colon - host_port) >= sizeof host) {
        fprintf(stderr, "host-sim: --listen wants HOST:PORT, got '%s'\n", host_port);
        return false;
    }
    memcpy(host, host_port, (size_t)(colon - host_port));
    host[colon - host_port] = '\0';
    struct addrinfo hints = {.ai_family = AF_INET, .ai_socktype = SOCK_STREAM, .ai_flags = AI_PASSIVE};
    struct addrinfo *res = NULL;
    if (getaddrinfo(host, colon + 1, &hints, &res) != 0) {
        fprintf(stderr, "host-sim: cannot resolve '%s'\n", host_port);
        return false;
    }
    s_listen_fd = socket(res->ai_family, res->ai_socktype, 0);
    const int one = 1;
    setsockopt(s_listen_fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (bind(s_listen_fd, res->ai_addr, res->ai_addrlen) != 0 || listen(s_listen_fd, 1) != 0) {
        fprintf(stderr, "host-sim: cannot listen on %s: %s\n", host_port, strerror(errno));
        freeaddrinfo(res);
        return false;
    }
    freeaddrinfo(res);
    return true;
}

bool hs_uart_open_pty(void)
{
    s_pty_fd = posix_openpt(O_RDWR | O_NOCTTY);
    if (s_pty_fd < 0 || grantpt(s_pty_fd) != 0 || unlockpt(s_pty_fd) != 0) {
        fprintf(stderr, "host-sim: no pseudo-terminal: %s\n", strerror(errno));
        return false;
    }
    printf("pty %s\n", ptsname(s_pty_fd));
    fflush(stdout);
    return true;
}

int hs_uart_poll_fd(void)
{
    if (s_pty_fd >= 0) {
        return s_pty_fd;
    }
    return s_conn_fd >= 0 ? s_conn_fd : s_listen_fd;
}

void hs_uart_on_readable(void)
{
    if (s_pty_fd < 0 && s_conn_fd < 0) {
        s_conn_fd = accept(s_listen_fd, NULL, NULL);
        if (s_conn_fd >= 0) {
            const int one = 1; /* answers must not wait for Nagle */
            setsockopt(s_conn_fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        }
        return;
    }
    const int fd = hs_uart_poll_fd();
    uint8_t buf[256];
    const ssize_t n = read(fd, buf, sizeof buf);
    if (n <= 0) {
        if (s_conn_fd >= 0) { /* client left: wait for the next one */
            close(s_conn_fd);
            s_conn_fd = -1;
        }
        return;
    }
    const uint32_t now = km_hal_time_now();
    for (ssize_t i = 0; i < n; i++) {
        if (s_rx) {
            s_rx(s_rx_ctx, buf[i], now, false);
        }
    }
}

bool km_hal_uart_init(uint32_t baud, km_uart_rx_handler_t handler, void *ctx)
{
    (void)baud; /* bytes over TCP have no line rate */
    s_rx = handler;
    s_rx_ctx = ctx;
    return true;
}

bool km_hal_uart_send(const uint8_t *data, uint16_t len)
{
    const int fd = s_pty_fd >= 0 ? s_pty_fd : s_conn_fd;
    if (fd < 0) {
        return true; /* nobody listening: the bytes go nowhere, as on an open wire */
    }
    size_t off = 0;
    while (off < len) {
        const ssize_t n = write(fd, data + off, len - off);
        if (n <= 0) {
            if (errno == EINTR) {
                continue;
            }
            return false;
        }
        off += (size_t)n;
    }
    return true;
}

bool km_hal_uart_tx_busy(void)
{
    return false; /* send() writes the whole buffer before returning */
}
