/* SPDX-License-Identifier: Apache-2.0 */
/* The firmware application (km_app.h): one main loop, the RX byte and
 * answer timer interrupts; answers timed from the frame's end tick; the
 * loop never waits on the bus (docs/app-design.md). */
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
#include "km_update_proto.h"

#define KM_APP_TICK_US KM_CONTROL_TICK_US /* control tick: 1 kHz */
#define KM_APP_RX_BUDGET 64u              /* bytes parsed per loop pass: bounds tick jitter */
#define KM_APP_RX_DEFER_MAX 12u /* a frame's end parses at most this many bytes a tick left queued */
#define KM_APP_WATCHDOG_MS 500u
#define KM_APP_FLASH_QUIET_US 50000u /* bus silence before idle flash work */
#define KM_APP_CONFIRM_US 1000000u   /* service before the boot is confirmed (docs/update.md §3a) */
/* A tick's wake-up looks for idle flash work on one tick in 4 (the 3rd),
 * the boards' slower jobs on others (docs/benchmarks.md "Control tick"). */
#define KM_APP_FLASH_EVERY_MASK 3u
#define KM_APP_FLASH_SLOT 2u

/* The receive interrupt's state: its frame tracker (docs/benchmarks.md "Per
 * byte") and the queue, one base address for a byte's fast path. */
typedef struct {
    km_rx_track_t track;
    km_rx_queue_t q;
} prv_rx_t;
static prv_rx_t s_rx;
static km_parser_t s_parser;
static km_parser_out_t s_out; /* the frame the parser hands out: a view */
static km_servo_t s_servo;
/* The answer, built and sent from here: the TX path's from arming to tx_busy's end. */
static km_reply_t s_reply;
static km_control_t s_control;
static km_control_params_t s_params; /* the control registers, decoded */
/* The fault log outlives a reset, not a power loss (.noinit). */
#if KM_FEATURE_EXT
static km_fault_log_t s_fault_log __attribute__((section(".noinit")));
#endif
/* The main loop's and its interrupts' scalars in one object: every
 * function reaches them from one base (docs/footprint.md "STM32G031F6"). */
typedef struct {
    volatile bool wake; /* set by the RX interrupt when the main loop must parse */
    volatile bool tx_armed;
    volatile bool answer_started;
    /* Why the parser is held, one byte so that "held at all" is one load: a
     * frame that may be answered, waiting for the answer on the wire to end (no
     * frame is parsed meanwhile), and a 0x02 restart pending. */
    uint8_t rx_hold;
    bool boot_confirmed; /* km_board_boot_confirm() was called */
    bool store_prepare;  /* the store needs preparing in idle time this session */
    uint16_t tx_len;     /* bytes of s_reply armed or being sent */
    uint32_t params_gen; /* km_servo_params_gen() the control parameters were decoded at */
    uint32_t next_tick;  /* the next control tick's grid point, a period after the last one's */
    uint32_t tick_period;
    uint32_t ticks;           /* control ticks run since init */
    uint32_t armed_frame_end; /* the armed answer's frame end tick */
    uint32_t armed_delay_us;  /* and the delay it asked for */
    /* The answer that started, copied together by the timer interrupt. */
    volatile uint32_t answer_frame_end;
    volatile uint32_t answer_delay_us;
    volatile uint32_t answer_start; /* tick the answer's first byte was handed to the UART */
    volatile uint32_t tx_refused;   /* answers the UART would not take (diagnostic) */
    uint32_t frame_release;         /* the waiting frame's queue bytes, released once handled */
    uint32_t confirm_at;            /* tick at which the start is confirmed */
} prv_app_t;
static prv_app_t s_app;
#define PRV_HOLD_FRAME 1u
#define PRV_HOLD_RESTART 2u

/* The main loop must parse: woken (docs/benchmarks.md "Per byte"). */
static void ISR_rx_wake(void)
{
    s_app.wake = true;
    km_hal_wake();
}

/* A received byte (docs/benchmarks.md "Per byte"): queued (after a loss or
 * into a full queue by the queue's rare path), the main loop woken only when
 * the tracker asks. */
static void ISR_rx_byte(void *ctx, uint8_t byte, uint32_t tick, bool lost)
{
    (void)ctx;
    prv_rx_t *rx = &s_rx;
    __asm__("" : "+r"(rx)); /* one base register for every field, not a literal each */
    km_rx_queue_push(&rx->q, byte, tick, lost);
    if (km_rx_track_byte(&rx->track, byte, tick, lost)) {
        ISR_rx_wake();
    }
}

static void ISR_answer_due(void *ctx)
{
    (void)ctx;
    s_app.tx_armed = false;
    if (km_hal_uart_send(s_reply.bytes, s_app.tx_len)) {
        s_app.answer_start = km_hal_time_now();
        s_app.answer_frame_end = s_app.armed_frame_end;
        s_app.answer_delay_us = s_app.armed_delay_us;
        s_app.answer_started = true;
        km_hal_wake();
    } else {
        s_app.tx_refused++;
    }
}

/* The receive state through a register (as prv_control()). */
static inline prv_rx_t *prv_rx(void)
{
    prv_rx_t *rx = &s_rx;
    __asm__("" : "+r"(rx));
    return rx;
}

/* Microseconds to ticks at the hal's compile-time rate (KM_HAL_TICK_MHZ):
 * no build, with LTO or without, pays a call or a division for it. */
static uint32_t prv_us_to_ticks(uint32_t us)
{
    return us * KM_HAL_TICK_MHZ;
}

/* Ticks to whole microseconds (no division for a 1 MHz tick, as every hal's). */
static uint32_t prv_ticks_to_us(uint32_t ticks)
{
#if KM_HAL_TICK_MHZ == 1
    return ticks;
#else
    return ticks / KM_HAL_TICK_MHZ;
#endif
}

/* Arms the timer to send s_app.tx_len bytes of s_reply `delay_us` after `frame_end`. */
static void prv_arm_answer(uint32_t frame_end, uint32_t delay_us)
{
    s_app.tx_armed = true;
    s_app.armed_frame_end = frame_end;
    s_app.armed_delay_us = delay_us;
    km_hal_timer_at(frame_end + prv_us_to_ticks(delay_us), ISR_answer_due, NULL);
}

/* Measurement hook after each answer started; the QEMU timing image overrides it. */
__attribute__((weak)) void km_app_answer_started(uint32_t frame_end, uint32_t started, uint32_t delay_us)
{
    (void)frame_end;
    (void)started;
    (void)delay_us;
}

/* Hands the last answer's timing to the hook (top of a pass, after each frame). */
static void prv_report_answer(void)
{
    if (!s_app.answer_started) {
        return;
    }
    /* one consistent record */
    const uint32_t irq = km_hal_irq_lock();
    const uint32_t frame_end = s_app.answer_frame_end;
    const uint32_t start = s_app.answer_start;
    const uint32_t delay_us = s_app.answer_delay_us;
    s_app.answer_started = false;
    km_hal_irq_restore(irq);
    km_app_answer_started(frame_end, start, delay_us);
}

/* Hands s_out's frame to the dispatcher and arms its answer; false: it may be answered and s_reply is on the
 * wire, so it waits (docs/app-design.md). */
static bool prv_on_frame(void)
{
    const km_frame_view_t *frame = &s_out.frame;
    bool held = false;
    if (km_servo_may_answer(&s_servo, frame)) {
        km_hal_timer_cancel(); /* then s_reply is armed-and-unsent or already sending */
        held = s_app.tx_armed; /* no interrupt changes it any more */
        if (!held && km_hal_uart_tx_busy()) {
            return false;
        }
    }
    km_servo_handle_view(&s_servo, frame, &s_reply);
    if (s_reply.len > 0) {
        s_app.tx_len = s_reply.len;
        prv_arm_answer(frame->end_tick, s_reply.delay_us);
    } else if (held) {
        prv_arm_answer(s_app.armed_frame_end, s_app.armed_delay_us);
    }
    prv_report_answer();
    return true;
}

static void prv_on_events(unsigned events)
{
    /* checksum errors come before the call's frame: the ID in force now */
    if ((events & KM_PARSE_CHECKSUM_ERR) && km_parser_take_checksum_error(&s_parser, km_servo_id(&s_servo))) {
        km_servo_note_checksum_error(&s_servo);
    }
    if ((events & KM_PARSE_FRAME) && !prv_on_frame()) {
        s_app.rx_hold |= PRV_HOLD_FRAME;
    }
}

/* True while the parser must not be fed: a restart or a waiting frame. */
static inline __attribute__((always_inline)) bool prv_rx_blocked(void)
{
    return s_app.rx_hold != 0u;
}

/* The waiting frame, once the answer on the wire has ended: handled, its queue bytes released. */
static void prv_take_waiting_frame(void)
{
    if ((s_app.rx_hold & PRV_HOLD_FRAME) != 0u && prv_on_frame()) {
        s_app.rx_hold &= (uint8_t)~PRV_HOLD_FRAME;
        km_rx_queue_release(&prv_rx()->q, s_app.frame_release);
        s_app.frame_release = 0u;
    }
}

/* True while the queued bytes are a short frame still arriving, not woken
 * for: the tracker inside one (its header or counted body), its newest byte
 * within the gap, and what is queued plus what is still to come at most
 * KM_APP_RX_DEFER_MAX bytes. The frame's end wakes the loop, which parses
 * the run at once; a wake-up for the tick leaves it queued. A longer frame
 * is parsed at the tick as it arrives, so its end parses little
 * (docs/benchmarks.md "Control tick"). */
static bool prv_rx_mid_frame(void)
{
    const km_rx_track_t *track = &prv_rx()->track;
    const unsigned state = track->state;
    if (state == KM_TRACK_HUNT || state == KM_TRACK_EVERY) {
        return false;
    }
    const uint32_t left = state == KM_TRACK_COUNT ? track->left : 0u;
    return left + km_rx_queue_count(&prv_rx()->q) <= KM_APP_RX_DEFER_MAX &&
           km_hal_time_now() - track->last_tick <= track->gap_ticks; /* the clock read last */
}

/* Runs of bytes from the RX queue to the parser, frames as views of the queue. */
static void prv_drain_rx(void)
{
    uint32_t budget = KM_APP_RX_BUDGET;
    km_rx_run_t run;
    const bool woken = s_app.wake;
    s_app.wake = false; /* before looking: a later byte's wake-up is kept */
    while (budget > 0u && !prv_rx_blocked() && km_rx_queue_peek(&prv_rx()->q, &run)) {
        if (!woken && budget == KM_APP_RX_BUDGET && prv_rx_mid_frame()) {
            return; /* the first run: a frame still arriving stays queued */
        }
        if (run.lost) {
            km_parser_overrun(&s_parser);
        }
        uint32_t used;
        const unsigned events = km_parser_feed_bytes(&s_parser, run.bytes, run.ticks,
                                                     run.n < budget ? run.n : budget, &used, &s_out);
        if (events != 0u) {
            prv_on_events(events);
        }
        if ((s_app.rx_hold & PRV_HOLD_FRAME) != 0u) {
            s_app.frame_release = used; /* the frame may be a view of these bytes */
            return;
        }
        km_rx_queue_release(&prv_rx()->q, used);
        budget -= used;
    }
    if (!prv_rx_blocked() && !km_parser_empty(&s_parser)) { /* empty: no time read, no call */
        const unsigned events = km_parser_poll_view(&s_parser, km_hal_time_now(), &s_out);
        if (events != 0u) {
            prv_on_events(events);
        }
    }
}

/* 0x02 restart: due once an earlier answer has gone out. */
static inline __attribute__((always_inline)) bool prv_restart_ready(void)
{
    return s_app.rx_hold == PRV_HOLD_RESTART && !s_app.tx_armed && !km_hal_uart_tx_busy();
}

/* The control state through a register: the inlined control code then reaches
 * its fields from one base, not one literal address each (docs/footprint.md "STM32G031F6"). */
static inline km_control_t *prv_control(void)
{
    km_control_t *control = &s_control;
    __asm__("" : "+r"(control));
    return control;
}

/* The control registers in engineering units, decoded again after a change. */
static const km_control_params_t *prv_params(void)
{
    const uint32_t gen = km_servo_params_gen(&s_servo);
    if (gen != s_app.params_gen) {
        km_servo_control_params(&s_servo, &s_params);
        s_app.params_gen = gen;
    }
    return &s_params;
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

/* One control tick `dt_ticks` of the grid after the last: sensors, step,
 * live values, fault log, bridge (noinline: the benches' landmark under LTO). */
static __attribute__((noinline)) void prv_control_tick(uint32_t dt_ticks)
{
    km_sensors_t sensors;
    km_live_t live;
    km_bridge_t bridge;
    km_hal_sensors_read(&sensors);
    km_control_step(prv_control(), &sensors, prv_params(), prv_ticks_to_us(dt_ticks), &live, &bridge);
    km_servo_set_live(&s_servo, &live);
#if KM_FEATURE_EXT
    km_fault_log_record(&s_fault_log, &live);
#endif
    prv_apply_bridge(&bridge);
}

/* ---- what the dispatcher calls --------------------------------------- */

/* Store work only with the bridge not driving (docs/app-design.md "Flash
 * work and the bridge"). */
static bool prv_bridge_driving(void)
{
    return s_control.bridge.mode == KM_BRIDGE_PWM;
}

static bool prv_ops_commit(void *ctx, const uint8_t *addrs, const uint32_t *values, uint8_t n)
{
    (void)ctx;
    if (prv_bridge_driving()) {
        km_hal_motor_brake();
    }
    return km_app_userdata_commit(addrs, values, n);
}

/* One step of idle-time store work on a silent bus; true if it did flash work. */
static bool prv_idle_flash_work(uint32_t now)
{
    if (prv_bridge_driving() || !km_rx_queue_empty(&prv_rx()->q) ||
        now - s_parser.last_tick < prv_us_to_ticks(KM_APP_FLASH_QUIET_US)) {
        return false;
    }
    if (s_app.store_prepare) {
        s_app.store_prepare = km_app_userdata_prepare();
        if (s_app.store_prepare) {
            return true;
        }
    }
    return km_app_userdata_maintain(); /* prepared (or given up): compaction ahead at once */
}

static void prv_ops_restart(void *ctx)
{
    (void)ctx;
    s_app.rx_hold |= PRV_HOLD_RESTART;
}

static bool prv_ops_request(void *ctx, const km_request_t *req)
{
    (void)ctx;
    return km_control_request(prv_control(), req, prv_params());
}

/* 0x78 in the application (docs/update.md §4): STATUS, or ENTER the bootloader. */
static bool prv_ops_update(void *ctx, const uint8_t *body, uint8_t n, uint8_t *answer, uint8_t *answer_len)
{
    km_update_answer_t a;
    km_update_app_frame(body, n, &a);
    *answer_len = 0u;
    if (a.action == KM_UPD_ACT_EXCEPTION) {
        return false;
    }
    if (a.action == KM_UPD_ACT_ENTER) {
        // cppcheck-suppress knownConditionTrueFalse
        if (!km_board_boot_request(km_servo_id(&s_servo), km_servo_active_baud(&s_servo))) {
            return false;
        }
        prv_ops_restart(ctx);
        return true;
    }
    if (a.len > KM_UPDATE_ANSWER_MAX) {
        return false;
    }
    memcpy(answer, a.body, a.len);
    *answer_len = a.len;
    return true;
}

#if KM_FEATURE_EXT
/* 0x7F of the fault log: the summary, or entry n (zeros when not held). */
static bool prv_ops_ext_read(void *ctx, uint8_t addr, uint8_t *out, uint8_t *n)
{
    (void)ctx;
    if (addr == KM_EXT_FAULT_SUMMARY) {
        *n = (uint8_t)km_fault_log_summary(&s_fault_log, out);
        return true;
    }
    const uint8_t idx = (uint8_t)(addr - KM_EXT_FAULT_ENTRY);
    if (addr < KM_EXT_FAULT_ENTRY || idx >= KM_EXT_FAULT_ENTRIES) {
        return false;
    }
    km_fault_entry_t e;
    if (!km_fault_log_get(&s_fault_log, idx, &e)) {
        memset(&e, 0, sizeof e);
    }
    *n = (uint8_t)km_fault_log_entry_bytes(&e, out);
    return true;
}

_Static_assert(KM_FAULT_ENTRY_SIZE <= KM_EXT_VALUE_MAX && KM_FAULT_SUMMARY_SIZE <= KM_EXT_VALUE_MAX,
               "a fault-log value must fit the extension answer");
_Static_assert(KM_EXT_FAULT_ENTRIES == KM_FAULT_LOG_LEN, "one extension register per fault-log entry");
#endif

/* No bootloader unless the board says so (a board with one defines it). */
__attribute__((weak)) bool km_board_boot_request(uint8_t id, uint32_t baud)
{
    (void)id;
    (void)baud;
    return false;
}

/* No bootloader, no trial to confirm (a board with one defines it). */
__attribute__((weak)) void km_board_boot_confirm(void)
{
}

/* Prepare only a store that needs formatting (a board may ask for more). */
__attribute__((weak)) bool km_board_store_prepare_each_boot(void)
{
    return false;
}

/* docs/update.md §3a: confirms the start once, after KM_APP_CONFIRM_US. */
static void prv_confirm_boot(uint32_t now)
{
    if (!s_app.boot_confirmed && (int32_t)(now - s_app.confirm_at) >= 0) {
        s_app.boot_confirmed = true;
        km_board_boot_confirm();
    }
}

static const km_servo_ops_t s_ops = {
    .commit = prv_ops_commit,
    .restart = prv_ops_restart,
    .request = prv_ops_request,
    .update = prv_ops_update,
#if KM_FEATURE_EXT
    .ext_read = prv_ops_ext_read,
#endif
    .ctx = NULL,
};

/* Opens the bus at the stored baud, else at a fresh servo's (ext 0x03 tells). */
static uint32_t prv_open_bus(uint32_t baud)
{
    if (km_hal_uart_init(baud, ISR_rx_byte, NULL)) {
        return baud;
    }
    const uint32_t fallback = km_reg_default(KM_REG_BAUD, km_board_product()) * 100u;
    (void)km_hal_uart_init(fallback, ISR_rx_byte, NULL); /* every board makes 115200 */
    return fallback;
}

/* noinline: its boot-time locals off the main loop's stack (docs/footprint.md "STM32G031F6"). */
__attribute__((noinline)) void km_app_init(void)
{
    s_app.tx_armed = false;
    s_app.answer_started = false;
    s_app.tx_refused = 0;
    s_app.rx_hold = 0u;
    s_app.frame_release = 0u;
    s_app.boot_confirmed = false;

    km_hal_system_init();
    /* first: a hang anywhere later resets */
    km_hal_watchdog_start(KM_APP_WATCHDOG_MS);
    km_hal_time_init();
    km_hal_motor_init();
    km_hal_sensors_init();

    const km_product_t *product = km_board_product();
    uint32_t persisted[KM_USERDATA_MAX];
    const km_store_mount_t mount = km_app_userdata_mount(km_board_flash(), product, persisted);
    km_servo_init(&s_servo, product, persisted, km_hal_entropy(), &s_ops);
    km_servo_set_userdata_source(&s_servo, (uint8_t)mount);
    s_app.store_prepare = mount != KM_STORE_MOUNT_ERR_ARG &&
                          (mount != KM_STORE_MOUNT_LOADED || km_board_store_prepare_each_boot());
#if KM_FEATURE_EXT
    km_servo_set_reset_cause(&s_servo, (uint8_t)km_hal_reset_cause());
    (void)km_fault_log_boot(&s_fault_log);
#endif
    km_servo_control_params(&s_servo, &s_params);
    s_app.params_gen = km_servo_params_gen(&s_servo);
    km_control_init(prv_control(), &s_params);

    km_rx_queue_init(&prv_rx()->q);
    const uint32_t baud = prv_open_bus(km_servo_active_baud(&s_servo));
    km_servo_set_active_baud(&s_servo, baud);
    /* docs/protocol-decisions.md "Inter-byte gap"; the slot floor is 0 */
    km_parser_init(&s_parser, prv_us_to_ticks(km_parser_default_gap_us(baud)));
    prv_rx()->track.gap_ticks = s_parser.gap_ticks;

    s_app.ticks = 0u;
    const uint32_t now = km_hal_time_now();
    s_app.tick_period = prv_us_to_ticks(KM_APP_TICK_US);
    s_app.next_tick = now; /* the first tick at once, a period after the grid's point before it */
    s_app.confirm_at = now + prv_us_to_ticks(KM_APP_CONFIRM_US);
}

/* Emulated buses: the gap floor raises the parser's rule at the open baud. */
void km_app_set_bus_floors(uint32_t gap_floor_us, uint32_t slot_floor_us)
{
    km_servo_set_slot_floor_us(&s_servo, slot_floor_us);
    uint32_t gap_us = km_parser_default_gap_us(km_servo_active_baud(&s_servo));
    if (gap_us < gap_floor_us) {
        gap_us = gap_floor_us;
    }
    km_parser_set_gap(&s_parser, prv_us_to_ticks(gap_us));
    prv_rx()->track.gap_ticks = s_parser.gap_ticks;
}

/* True when the control tick is due at `now`. */
static bool prv_tick_due(uint32_t now)
{
    return (int32_t)(now - s_app.next_tick) >= 0;
}

/* The grid time, in ticks, from the last control tick to this one, due at
 * `now`, and the next grid point: a period, or, a tick half a period late,
 * up to just before this wake-up, where the grid moves (docs/benchmarks.md
 * "Control tick"). */
static uint32_t prv_next_tick(uint32_t now)
{
    const uint32_t period = s_app.tick_period, due = s_app.next_tick;
    if (now - due < period / 2u) {
        s_app.next_tick = due + period;
        return period;
    }
    const uint32_t at = now - period / 8u; /* this tick's grid point, moved */
    s_app.next_tick = at + period;
    return at - due + period;
}

/* Sleeps, under the caller's lock, until something needs a pass of the
 * main loop: while the parser is blocked, the next interrupt (the answer on
 * the wire may have ended); else a frame's end, an answer started or the
 * control tick (docs/benchmarks.md "Per byte"); `queued`: a frame still
 * arriving waits in the queue. */
static void prv_sleep(uint32_t irq, bool queued)
{
    if (prv_rx_blocked()) {
        km_hal_idle();
        return;
    }
    if (!queued) { /* else a frame arriving: the tracker is ahead of the parser */
        km_rx_track_sync(&prv_rx()->track, &s_parser); /* every byte is parsed */
    }
    do {
        km_hal_sleep(irq); /* the interrupts run in it; the caller restores irq */
    } while (!s_app.wake && !s_app.answer_started && !prv_tick_due(km_hal_time_now()));
}

/* The control tick due at `now`, the watchdog and the boot's confirmation;
 * true when the pass may go on to idle work and sleep: nothing that only
 * the top of a pass handles came meanwhile (a frame's end by its gap, an
 * answer started), so a tick's wake-up is one pass (docs/benchmarks.md
 * "Control tick"). */
static bool prv_tick(uint32_t now)
{
    const uint32_t dt_ticks = prv_next_tick(now);
    s_app.ticks++;
    prv_control_tick(dt_ticks);
    km_hal_watchdog_kick();
    prv_confirm_boot(now);
    return km_parser_empty(&s_parser) && !s_app.answer_started;
}

/* Sleeps unless work came: checked under the lock, WFI still wakes on a pending IRQ. */
static void prv_sleep_unless_work(void)
{
    const uint32_t irq = km_hal_irq_lock();
    const bool queued = !km_rx_queue_empty(&prv_rx()->q);
    const bool rx_work = !prv_rx_blocked() && queued && (s_app.wake || !prv_rx_mid_frame());
    const bool tx_work = (s_app.rx_hold & PRV_HOLD_FRAME) != 0u && !km_hal_uart_tx_busy();
    if (!rx_work && !tx_work && !prv_restart_ready()) {
        prv_sleep(irq, queued);
    }
    km_hal_irq_restore(irq);
}

/* One pass (noinline: watched under LTO, docs/footprint.md "LTO"). */
__attribute__((noinline)) void km_app_poll(void)
{
    prv_report_answer();
    prv_take_waiting_frame();
    prv_drain_rx();
    if (prv_restart_ready()) {
        km_hal_system_reset();
    }
    const uint32_t now = km_hal_time_now();
    bool flash_slot = true; /* a wake-up without a tick may always look */
    if (prv_tick_due(now)) {
        if (!prv_tick(now)) {
            return;
        }
        flash_slot = (s_app.ticks & KM_APP_FLASH_EVERY_MASK) == KM_APP_FLASH_SLOT;
    }
    if (!flash_slot || !prv_idle_flash_work(now)) {
        prv_sleep_unless_work();
    }
}

#if KM_FEATURE_EXT
km_fault_log_t *km_app_fault_log(void)
{
    return &s_fault_log;
}
#endif

uint32_t km_app_tx_refused(void)
{
    return s_app.tx_refused;
}

const km_servo_t *km_app_servo(void)
{
    return &s_servo;
}

/* Diagnostics for tests/bench/m0/bench_m0_app.c (km_app.h should declare them). */
const km_parser_stats_t *km_app_parser_stats(void);
uint32_t km_app_rx_dropped(void);

const km_parser_stats_t *km_app_parser_stats(void)
{
    return &s_parser.stats;
}

uint32_t km_app_rx_dropped(void)
{
    return s_rx.q.dropped;
}

_Noreturn void km_app_run(void)
{
    km_app_init();
    for (;;) {
        km_app_poll();
    }
}
