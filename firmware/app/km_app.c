/* The firmware application (see km_app.h). One main loop, three interrupt
 * handlers (RX byte, answer timer, and whatever the hal uses for TX):
 *
 *   RX IRQ --byte+tick--> km_rx_queue --(main loop, bounded)--> parser
 *     --frame--> dispatcher --answer + delay--> one-shot timer IRQ --> UART TX
 *
 * The answer starts exactly `delay_us` after the frame's last byte because
 * the timer is armed at end_tick + delay, end_tick being stamped by the RX
 * interrupt, not by when the main loop got to the frame. The main loop runs
 * the control tick every KM_APP_TICK_US and compacts the store when idle. */
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "km_app.h"
#include "km_app_userdata.h"
#include "km_control.h"
#include "km_hal_motor.h"
#include "km_hal_sensors.h"
#include "km_hal_system.h"
#include "km_hal_time.h"
#include "km_hal_uart.h"
#include "km_parser.h"
#include "km_rx_queue.h"
#include "km_servo.h"

#define KM_APP_TICK_US 1000u      /* control tick */
#define KM_APP_RX_BUDGET 64u      /* bytes parsed per loop pass: bounds tick jitter */
#define KM_APP_WATCHDOG_MS 500u

/* Lowest inter-byte gap that drops a frame. A real UART delivers a frame's
 * bytes at line rate, so the parser's default (10 byte times, >= 1 ms)
 * holds. An emulated UART (QEMU, host-sim) delivers them when the host
 * schedules the emulator, which can pause for milliseconds between two
 * bytes of one frame: simulated boards raise this floor at build time. */
#ifndef KM_APP_GAP_MIN_US
#define KM_APP_GAP_MIN_US 1000u /* the parser default's own floor */
#endif

static km_rx_queue_t s_rxq;
static km_parser_t s_parser;
static km_frame_t s_frame;
static km_servo_t s_servo;
static km_reply_t s_reply;
static km_control_t s_control;
static uint32_t s_last_control_tick;

/* The answer being sent: owned by the TX path from arming until tx_busy ends. */
static uint8_t s_tx[KM_FRAME_MAX];
static uint16_t s_tx_len;
static volatile bool s_tx_armed;
static uint32_t s_answer_frame_end;      /* tick of the answered frame's last byte */
static uint32_t s_answer_delay_us;       /* the delay it asked for */
static volatile uint32_t s_answer_start; /* tick the answer's first byte was handed to the UART */
static volatile bool s_answer_started;
static bool s_restart_pending;

static void ISR_rx_byte(void *ctx, uint8_t byte, uint32_t tick, bool lost)
{
    (void)ctx;
    km_rx_queue_push(&s_rxq, byte, tick, lost);
}

static void ISR_answer_due(void *ctx)
{
    (void)ctx;
    s_answer_start = km_hal_time_now();
    s_answer_started = true;
    (void)km_hal_uart_send(s_tx, s_tx_len);
    s_tx_armed = false;
}

/* Ticks per microsecond, fixed at init: the hal tick is a whole number of
 * MHz, so the per-tick conversions below are one 32-bit multiply or divide
 * (a 64-bit divide is a libgcc call on Cortex-M0, and this runs every tick). */
static uint32_t s_ticks_per_us = 1u;

static uint32_t prv_us_to_ticks(uint32_t us)
{
    return us * s_ticks_per_us;
}

static void prv_schedule_answer(const km_reply_t *reply, uint32_t frame_end)
{
    /* A master waits for an answer before the next question, so a previous
     * answer is always gone by now; if not (a master that does not wait), the
     * new answer replaces the old one rather than colliding with it. */
    while (km_hal_uart_tx_busy()) {
    }
    km_hal_timer_cancel();
    memcpy(s_tx, reply->bytes, reply->len);
    s_tx_len = reply->len;
    s_tx_armed = true;
    s_answer_frame_end = frame_end;
    s_answer_delay_us = reply->delay_us;
    km_hal_timer_at(frame_end + prv_us_to_ticks(reply->delay_us), ISR_answer_due, NULL);
}

/* Measurement hook, called from the main loop after each answer started:
 * the frame's end tick, the tick the answer was handed to the UART, and the
 * delay asked for. Empty here; the QEMU timing image (boards/qemu-microbit/
 * test/answer_timing.c) prints it to measure answer-delay accuracy. */
__attribute__((weak)) void km_app_answer_started(uint32_t frame_end, uint32_t started, uint32_t delay_us)
{
    (void)frame_end;
    (void)started;
    (void)delay_us;
}

/* Hands the last answer's timing to the hook. Called at the top of the main
 * loop and right after each frame: with a delay of 0 the answer starts while
 * the frame is being handled, and the next frame of the same drain pass
 * would otherwise overwrite the record before it is reported. */
static void prv_report_answer(void)
{
    if (s_answer_started) {
        s_answer_started = false;
        km_app_answer_started(s_answer_frame_end, s_answer_start, s_answer_delay_us);
    }
}

static void prv_on_frame(void)
{
    km_servo_handle(&s_servo, &s_frame, &s_reply);
    if (s_reply.len > 0) {
        prv_schedule_answer(&s_reply, s_frame.end_tick);
    }
    prv_report_answer();
}

static void prv_on_events(unsigned events)
{
    if ((events & KM_PARSE_CHECKSUM_ERR) &&
        km_parser_take_checksum_error(&s_parser, km_servo_id(&s_servo))) {
        km_servo_note_checksum_error(&s_servo);
    }
    if (events & KM_PARSE_FRAME) {
        prv_on_frame();
    }
}

static void prv_drain_rx(void)
{
    uint8_t byte;
    uint32_t tick;
    uint8_t flags;
    for (unsigned n = 0; n < KM_APP_RX_BUDGET && km_rx_queue_pop(&s_rxq, &byte, &tick, &flags); n++) {
        if (flags & KM_RX_LOST) {
            km_parser_overrun(&s_parser);
        }
        prv_on_events(km_parser_feed(&s_parser, byte, tick, &s_frame));
    }
    prv_on_events(km_parser_poll(&s_parser, km_hal_time_now(), &s_frame));
}

static void prv_restart_when_sent(void)
{
    /* 0x02 restart has no answer, but an answer to an earlier frame may
     * still be on the wire: let it finish, then reset for real. */
    while (s_tx_armed || km_hal_uart_tx_busy()) {
    }
    km_hal_system_reset();
}

static km_control_config_t prv_control_config(void)
{
    km_control_config_t cfg = {
        .zero_offset1 = (int16_t)km_servo_reg(&s_servo, KM_REG_ZERO_OFFSET1),
        .zero_offset2 = (int16_t)km_servo_reg(&s_servo, KM_REG_ZERO_OFFSET2),
        .config = (uint8_t)km_servo_reg(&s_servo, KM_REG_CONFIG),
        .torque_switch = (uint8_t)km_servo_reg(&s_servo, KM_REG_TORQUE_SWITCH),
    };
    return cfg;
}

static void prv_apply_bridge(const km_bridge_t *b)
{
    switch (b->mode) {
    case KM_BRIDGE_PWM:
        km_hal_motor_drive(b->pwm);
        break;
    case KM_BRIDGE_BRAKE:
        km_hal_motor_brake();
        break;
    default:
        km_hal_motor_free();
        break;
    }
}

static void prv_control_tick(uint32_t now)
{
    km_sensors_t sensors;
    km_live_t live;
    km_bridge_t bridge;
    const km_control_config_t cfg = prv_control_config();
    const uint32_t dt_ticks = now - s_last_control_tick;
    s_last_control_tick = now;
    km_hal_sensors_read(&sensors);
    km_control_step(&s_control, &sensors, &cfg, dt_ticks / s_ticks_per_us, &live, &bridge);
    km_servo_set_live(&s_servo, &live);
    prv_apply_bridge(&bridge);
}

/* ---- what the dispatcher calls --------------------------------------- */

static bool prv_ops_commit(void *ctx, const uint8_t *addrs, const uint32_t *values, uint8_t n)
{
    (void)ctx;
    return km_app_userdata_commit(addrs, values, n);
}

static void prv_ops_restart(void *ctx)
{
    (void)ctx;
    s_restart_pending = true;
}

static void prv_ops_request(void *ctx, const km_request_t *req)
{
    (void)ctx;
    const km_control_config_t cfg = prv_control_config();
    km_control_request(&s_control, req, &cfg);
}

static const km_servo_ops_t s_ops = {
    .commit = prv_ops_commit,
    .restart = prv_ops_restart,
    .request = prv_ops_request,
    .ctx = NULL,
};

_Noreturn void km_app_run(void)
{
    km_hal_system_init();
    km_hal_time_init();
    km_hal_motor_init();
    km_hal_sensors_init();
    s_ticks_per_us = km_hal_time_tick_hz() / 1000000u;

    const km_product_t *product = km_board_product();
    uint32_t persisted[KM_USERDATA_MAX];
    const km_store_mount_t mount = km_app_userdata_mount(km_board_flash(), product, persisted);
    km_servo_init(&s_servo, product, persisted, km_hal_entropy(), &s_ops);
    /* Register 0x0D tells the master where the user data came from; the
     * store's mount results are in the same order as KM_USERDATA_*. */
    km_servo_set_userdata_source(&s_servo, (uint8_t)mount);
    const km_control_config_t cfg = prv_control_config();
    km_control_init(&s_control, &cfg);

    const uint32_t baud = km_servo_active_baud(&s_servo);
    uint32_t gap_us = km_parser_default_gap_us(baud);
    if (gap_us < KM_APP_GAP_MIN_US) {
        gap_us = KM_APP_GAP_MIN_US;
    }
    km_parser_init(&s_parser, prv_us_to_ticks(gap_us));
    km_rx_queue_init(&s_rxq);
    (void)km_hal_uart_init(baud, ISR_rx_byte, NULL);
    km_hal_watchdog_start(KM_APP_WATCHDOG_MS);

    s_last_control_tick = km_hal_time_now();
    const uint32_t tick_period = prv_us_to_ticks(KM_APP_TICK_US);
    uint32_t next_tick = s_last_control_tick;
    for (;;) {
        prv_report_answer();
        prv_drain_rx();
        if (s_restart_pending) {
            prv_restart_when_sent();
        }
        const uint32_t now = km_hal_time_now();
        if ((int32_t)(now - next_tick) >= 0) {
            next_tick += tick_period;
            prv_control_tick(now);
            km_hal_watchdog_kick();
        } else if (!km_app_userdata_maintain()) {
            /* Check and sleep under the lock: WFI still wakes on an
             * interrupt that became pending after the check. */
            const uint32_t irq = km_hal_irq_lock();
            if (km_rx_queue_empty(&s_rxq) && !s_restart_pending) {
                km_hal_idle();
            }
            km_hal_irq_restore(irq);
        }
    }
}
