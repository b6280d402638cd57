/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: the servo bus over TCP (one client at a time) or a pseudo-terminal,
 * as a UART at the servo's baud (8N1): RX bytes stamped with their wire time,
 * TX busy until the last stop bit (docs/architecture.md "host-sim's UART"). */
#define _GNU_SOURCE /* posix_openpt, ptsname */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "hs_io.h"
#include "hs_wire.h"
#include "km_hal_time.h"
#include "km_hal_uart.h"
#include "km_rx_queue.h" /* KM_RX_QUEUE_SIZE: what the app can take between idles */

/* Host-side RX buffer, a power of two. */
#define HS_RX_BUF 4096u
#define HS_BITS_PER_BYTE 10u /* start + 8 data + stop */

static int s_listen_fd = -1;
static int s_conn_fd = -1;
static int s_pty_fd = -1;
static km_uart_rx_handler_t s_rx;
static void *s_rx_ctx;

static uint8_t s_rx_byte[HS_RX_BUF];
static uint64_t s_rx_due_ns[HS_RX_BUF]; /* when each byte's stop bit ends */
static uint32_t s_rx_head;              /* free-running; head - tail bytes waiting */
static uint32_t s_rx_tail;
static uint64_t s_wire_free_ns;                 /* the wire is free after the last buffered byte */
static uint32_t s_rx_budget = KM_RX_QUEUE_SIZE; /* bytes the app's queue surely takes */
static uint64_t s_byte_ns = (HS_BITS_PER_BYTE * 1000000000ull) / 115200u;
static uint64_t s_tx_end_ns; /* the last answer's last stop bit */
static bool s_tx_busy;       /* what tx_busy() last told the app */
static uint32_t s_wire_baud; /* the master's rate; 0 = the servo's own */
static uint32_t s_uart_baud = 115200u;
static bool s_report_baud;

void hs_uart_set_wire_baud(uint32_t baud)
{
    s_wire_baud = baud;
}

void hs_uart_set_report_baud(bool on)
{
    s_report_baud = on;
}

static uint32_t prv_wire_baud(void)
{
    return s_wire_baud != 0u ? s_wire_baud : s_uart_baud;
}

/* A descriptor handed over a restart's exec in the environment; -1 if none. */
static int prv_env_fd(const char *name)
{
    const char *v = getenv(name);
    if (v == NULL) {
        return -1;
    }
    char *end;
    errno = 0;
    const long fd = strtol(v, &end, 10);
    return (end == v || *end != '\0' || errno != 0 || fd < 0 || fd > INT_MAX) ? -1 : (int)fd;
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

/* --listen HOST:0: print the port the kernel chose, "port N" on stdout, for
 * sim/bus/servo-bus, which connects to it (docs/architecture.md "host-sim's
 * options"). */
static bool prv_report_chosen_port(const char *port_text)
{
    if (strcmp(port_text, "0") != 0) {
        return true;
    }
    struct sockaddr_in bound = {0};
    socklen_t len = sizeof bound;
    if (getsockname(s_listen_fd, (struct sockaddr *)&bound, &len) != 0) {
        fprintf(stderr, "host-sim: cannot read the port chosen: %s\n", strerror(errno));
        return false;
    }
    printf("port %u\n", (unsigned)ntohs(bound.sin_port));
    fflush(stdout);
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
    return prv_report_chosen_port(colon + 1);
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

static uint32_t prv_rx_waiting(void)
{
    return s_rx_head - s_rx_tail;
}

int hs_uart_poll_fd(void)
{
    const int bus = s_pty_fd >= 0 ? s_pty_fd : s_conn_fd;
    if (bus < 0) {
        return s_listen_fd;
    }
    return prv_rx_waiting() < HS_RX_BUF ? bus : -1; /* full: leave it in the socket */
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
    const int fd = s_pty_fd >= 0 ? s_pty_fd : s_conn_fd;
    const uint32_t room = HS_RX_BUF - prv_rx_waiting();
    if (room == 0u) {
        return;
    }
    uint8_t wire[HS_RX_BUF];
    uint8_t buf[HS_RX_BUF * HS_WIRE_GROWTH];
    const ssize_t got = read(fd, wire, room);
    if (got <= 0) {
        if (s_conn_fd >= 0) { /* client left: wait for the next one */
            close(s_conn_fd);
            s_conn_fd = -1;
        }
        return;
    }
    /* What this UART decodes from the master's bytes; past `room`: an overrun. */
    size_t n = hs_wire_garble(wire, (size_t)got, prv_wire_baud(), s_uart_baud, buf, sizeof buf);
    if (n > room) {
        n = room;
    }
    /* Each byte due a byte time after the one before (or now, wire free). */
    const uint64_t now = hs_time_real_ns();
    uint64_t due = s_wire_free_ns > now ? s_wire_free_ns : now;
    for (size_t i = 0; i < n; i++) {
        const uint32_t slot = s_rx_head & (HS_RX_BUF - 1u);
        s_rx_byte[slot] = buf[i];
        s_rx_due_ns[slot] = due;
        s_rx_head++;
        due += s_byte_ns;
    }
    s_wire_free_ns = due;
}

/* The TX-done "interrupt": the only place the busy flag changes. */
static void prv_tx_done_if_due(void)
{
    /* By the host's clock (the emulated one may be held). */
    if (s_tx_busy && hs_time_real_ns() >= s_tx_end_ns) {
        s_tx_busy = false;
    }
}

void hs_uart_rx_idle_begin(void)
{
    if (!s_tx_busy) {
        s_rx_budget = KM_RX_QUEUE_SIZE; /* the app drained its queue */
    }
    prv_tx_done_if_due();
}

static bool prv_rx_deliverable(void)
{
    return s_rx != NULL && s_rx_budget > 0u && prv_rx_waiting() > 0u;
}

bool hs_uart_rx_deliver_one(void)
{
    if (!prv_rx_deliverable()) {
        return false;
    }
    const uint32_t slot = s_rx_tail & (HS_RX_BUF - 1u);
    if (s_rx_due_ns[slot] > hs_time_now_ns()) {
        return false;
    }
    s_rx_tail++;
    s_rx_budget--;
    /* Stamped with its wire time, not now. */
    s_rx(s_rx_ctx, s_rx_byte[slot], (uint32_t)(s_rx_due_ns[slot] / 1000u), false);
    return true;
}

uint64_t hs_uart_hold_ns(void)
{
    /* A byte the budget cannot take yet does not hold the clock. */
    if (!prv_rx_deliverable()) {
        return UINT64_MAX;
    }
    return s_rx_due_ns[s_rx_tail & (HS_RX_BUF - 1u)];
}

static int64_t prv_us_until(uint64_t at_ns, uint64_t now_ns)
{
    return at_ns > now_ns ? (int64_t)((at_ns - now_ns + 999u) / 1000u) : 0;
}

int64_t hs_uart_due_in_us(uint64_t real_ns)
{
    int64_t due = -1;
    if (s_tx_busy) {
        /* TX done is an interrupt too. */
        due = prv_us_until(s_tx_end_ns, real_ns);
    }
    /* With the budget spent, the next byte waits for an idle after TX. */
    if (prv_rx_waiting() > 0u && (s_rx_budget > 0u || !s_tx_busy)) {
        const int64_t rx = prv_us_until(s_rx_due_ns[s_rx_tail & (HS_RX_BUF - 1u)], real_ns);
        if (due < 0 || rx < due) {
            due = rx;
        }
    }
    return due;
}

bool km_hal_uart_init(uint32_t baud, km_uart_rx_handler_t handler, void *ctx)
{
    if (baud == 0u) {
        return false;
    }
    /* The line rate is the servo's own baud register (0x10). */
    s_byte_ns = (HS_BITS_PER_BYTE * 1000000000ull + baud / 2u) / baud;
    s_uart_baud = baud;
    if (s_report_baud) {
        printf("baud %u\n", (unsigned)baud);
        fflush(stdout);
    }
    s_rx = handler;
    s_rx_ctx = ctx;
    return true;
}

bool km_hal_uart_send(const uint8_t *data, uint16_t len)
{
    if (len == 0u) {
        return true;
    }
    prv_tx_done_if_due();
    if (s_tx_busy) {
        return false; /* the contract: one send at a time */
    }
    /* Busy from the answer's due time (not a late wake) to its last stop bit. */
    uint64_t start = hs_timer_firing_due_ns();
    if (start == 0u) {
        start = hs_time_now_ns();
    }
    if (start < s_tx_end_ns) {
        start = s_tx_end_ns;
    }
    s_tx_end_ns = start + (uint64_t)len * s_byte_ns;
    s_tx_busy = true;
    const int fd = s_pty_fd >= 0 ? s_pty_fd : s_conn_fd;
    if (fd < 0) {
        return true; /* nobody listening: the bytes go nowhere, as on an open wire */
    }
    /* Written whole at once; tx_busy models the line rate. */
    uint8_t heard[512u * HS_WIRE_GROWTH];
    if (len > 512u) {
        len = 512u; /* longer than any answer of the protocol */
    }
    len = (uint16_t)hs_wire_garble(data, len, s_uart_baud, prv_wire_baud(), heard, sizeof heard);
    data = heard;
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
    /* The answer timer and TX done fire here too: an app may spin on this. */
    hs_timer_fire_due_now();
    prv_tx_done_if_due();
    return s_tx_busy;
}
