/* Cortex-M0 end-to-end instruction counts (tools/bench-m0): the firmware's
 * real main loop (firmware/app/km_app.c, km_app_init + km_app_poll) over
 * this board's time, flash and system drivers, with the bus UART, motor and
 * sensors replaced by the stand-ins below, so that the benchmark hands a
 * frame's bytes to the app's RX callback itself, exactly when it wants.
 *
 * Per frame: its bytes but the last are handed over and parsed, the loop
 * runs until a control tick has just happened (the next is 1 ms away, so
 * none can land in the measurement), then a region starts, the last byte
 * goes to the RX callback (what the UART interrupt calls, with its tick)
 * and the loop runs. The tool reads the instructions from the region's
 * start to the first entry of km_hal_timer_at (the answer timer armed) and
 * to the first entry of km_hal_idle (the loop has nothing left to do):
 * RX queue, parser, dispatcher, encoder and the app around them. The UART
 * interrupt's own register reads (uart.c) are not in it. Run under
 * -icount shift=0, so that time, and with it the tick, is a function of
 * the instructions executed: the counts are the same on every run. */
#include <stdbool.h>
#include <stdint.h>

#include "km_app.h"
#include "km_hal_motor.h"
#include "km_hal_sensors.h"
#include "km_hal_time.h"
#include "km_hal_uart.h"
#include "semihost.h"

void m0_begin(void);
void m0_end(void);
void m0_region_empty(void);
void m0_region_loop1000(void);

/* ---- stand-ins for the bus UART, motor and sensors ------------------- */

static km_uart_rx_handler_t s_rx;
static void *s_rx_ctx;
static volatile uint32_t s_sent;
static volatile uint32_t s_ticks;

bool km_hal_uart_init(uint32_t baud, km_uart_rx_handler_t handler, void *ctx)
{
    (void)baud;
    s_rx = handler;
    s_rx_ctx = ctx;
    return true;
}

/* A frame's last byte comes a control tick after the others: far above
 * the real gap rule, so the parser keeps the frame. */
uint32_t km_hal_uart_gap_floor_us(void)
{
    return 1000000u;
}

bool km_hal_uart_send(const uint8_t *data, uint16_t len)
{
    (void)data;
    (void)len;
    s_sent++;
    return true;
}

bool km_hal_uart_tx_busy(void)
{
    return false;
}

void km_hal_motor_init(void)
{
}

void km_hal_motor_drive(int16_t pwm)
{
    (void)pwm;
}

void km_hal_motor_free(void)
{
}

void km_hal_motor_brake(void)
{
}

void km_hal_sensors_init(void)
{
}

void km_hal_sensors_read(km_sensors_t *out)
{
    out->position = 0;
    out->current_ma = 120;
    out->voltage_mv = 7400;
    out->temperature_c10 = 250;
    out->faults = 0;
    s_ticks++;
}

/* ---- harness ----------------------------------------------------------- */

static bool s_failed;

static void m0h_say(const char *a, const char *b)
{
    km_semihost_write0(a);
    km_semihost_write0(b);
    km_semihost_write0("\n");
}

/* Runs the loop until a control tick has just happened. */
static void m0h_after_tick(void)
{
    const uint32_t t = s_ticks;
    while (s_ticks == t) {
        km_app_poll();
    }
}

static void m0h_frame(const char *name, uint8_t id, uint8_t cmd, const uint8_t *body, uint8_t n,
                      bool answer, bool changes)
{
    uint8_t f[KM_FRAME_MAX];
    f[0] = KM_HDR0;
    f[1] = KM_HDR1_COMMAND;
    f[2] = id;
    f[3] = (uint8_t)(n + 2u);
    f[4] = cmd;
    for (uint8_t i = 0; i < n; i++) {
        f[5u + i] = body[i];
    }
    f[5u + n] = km_checksum(&f[2], 3u + (uint32_t)n);
    const unsigned len = 6u + n;
    for (unsigned i = 0; i + 1u < len; i++) {
        s_rx(s_rx_ctx, f[i], km_hal_time_now(), false);
        if (i % 32u == 31u) {
            km_app_poll(); /* the RX queue is smaller than a long frame */
        }
    }
    m0h_after_tick(); /* parses them, then the tick */
    const uint32_t sent = s_sent;
    const uint32_t gen = km_servo_params_gen(km_app_servo());
    m0h_say("region e2e_", name);
    const uint32_t now = km_hal_time_now();
    m0_begin();
    s_rx(s_rx_ctx, f[len - 1u], now, false);
    km_app_poll();
    km_app_poll();
    m0_end();
    m0h_after_tick(); /* the answer goes out at its delay */
    m0h_after_tick();
    /* An answer went out, or (writes) a register changed: the frame was
     * handled, not lost. */
    const bool ok = answer ? s_sent != sent
                           : (km_servo_params_gen(km_app_servo()) != gen) == changes;
    km_semihost_write0("check e2e_");
    m0h_say(name, ok ? " ok" : " FAIL");
    if (!ok) {
        s_failed = true;
    }
}

int main(void)
{
    /* The count validated under -icount too (m0_markers.c). */
    m0h_say("region ", "empty");
    m0_region_empty();
    m0h_say("region ", "loop1000_inline");
    m0_region_loop1000();
    km_app_init();
    m0h_after_tick();
    m0h_after_tick();
    uint8_t b[KM_BODY_MAX] = {0};
    m0h_frame("ping", 0, 0x01, b, 0, true, false);
    b[0] = 0x13;
    m0h_frame("read_short_0x13", 0, 0x02, b, 1, true, false);
    b[0] = 0x0A;
    m0h_frame("read_long_0x0A", 0, 0x02, b, 1, true, false);
    b[0] = 0x46;
    m0h_frame("read_super_id_0x46", KM_ID_SUPER, 0x02, b, 1, true, false);
    b[0] = 0x5B;
    b[1] = 0x20;
    b[2] = 0x03;
    m0h_frame("write_0x5B", 0, 0x03, b, 3, false, true);
    b[0] = 0x12;
    b[1] = 0xF4;
    b[2] = 0x01;
    m0h_frame("write_persisted_0x12", 0, 0x03, b, 3, false, true);
    b[0] = 0x12;
    b[1] = 0xC8;
    b[2] = 0x00;
    m0h_frame("write_persisted_0x12_again", 0, 0x03, b, 3, false, true);
    b[0] = 0x65;
    b[1] = 0xC2;
    b[2] = 0x01;
    b[3] = 0xF4;
    b[4] = 0x01;
    m0h_frame("sync_write_0x04", 0, 0x04, b, 5, false, false);
    m0h_frame("sync_execute_0x84", KM_ID_BROADCAST, 0x84, b, 0, false, true);
    for (unsigned entries = 3; entries <= 49; entries += 46) {
        b[0] = 0x65;
        b[1] = 4;
        for (unsigned i = 0; i < entries; i++) {
            uint8_t *e = &b[2 + 5 * i];
            e[0] = (uint8_t)(i + 1u == entries ? 0u : i + 1u);
            e[1] = entries == 3 ? 0x90 : 0x5E; /* +40.0, +35.0 deg: a new target */
            e[2] = 0x01;
            e[3] = 0xF4;
            e[4] = 0x01;
        }
        m0h_frame(entries == 3 ? "multi_write_0x83_3" : "multi_write_0x83_49", KM_ID_BROADCAST,
                  0x83, b, (uint8_t)(2u + 5u * entries), false, false); /* a move: no register changes */
    }
    b[0] = 0x01;
    m0h_frame("read_status_0x01", 0, 0x02, b, 1, true, false);
    km_semihost_write0(s_failed ? "bench-m0 FAIL\n" : "bench-m0 done\n");
    km_semihost_exit(s_failed ? 1 : 0);
}
