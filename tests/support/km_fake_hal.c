/* SPDX-License-Identifier: Apache-2.0 */
/* The fake board behind tests/unit/app/ and the fuzz_app target: every hal
 * contract over a discrete-event world in virtual time (see km_fake_hal.h). */
#define _POSIX_C_SOURCE 200809L /* sigsetjmp, sigaction, alarm */
#include "km_fake_hal.h"

#include <setjmp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "km_app.h"
#include "km_hal_motor.h"
#include "km_hal_sensors.h"
#include "km_hal_time.h"
#include "km_hal_uart.h"

#include <unistd.h>

kf_world_t kf_world;

static sigjmp_buf s_run_env;
static bool s_in_run;
static bool s_in_isr;

enum { KF_JUMP_RESET = 1, KF_JUMP_SPUN = 2 };

/* ---- the product and the flash the app boots with ---------------------- */

static const km_product_t s_product = {
    .model = "KM-FAKE-BOARD",
    .firmware_version = 0x00111002u,
    .variant = KM_VARIANT_ENCODER,
    .max_current_ma = 2000,
    .max_speed_dps = 600,
    .zero_offset1 = 0,
    .angle_min = 0,
    .angle_max = 0,
    .voltage_high_v = 14,
    .voltage_low_v = 6,
    .current_threshold_ma = 1800,
    .baud_min_100 = 96,
    .baud_max_100 = 10000,
    .current_max_ma = 3000,
    .speed_max_dps = 1000,
    .travel_min = -32000,
    .travel_max = 32000,
    .zero_offset2_max = 300,
    .voltage_max_v = 30,
};

/* The potentiometer product of the simulated boards
 * (boards/sim-common/km_sim_product.c), for tests that need the travel
 * end and its position check (kf_world.pot_product). */
static const km_product_t s_product_pot = {
    .model = "KM-FAKE-POT",
    .firmware_version = 0x00111002u,
    .variant = KM_VARIANT_POTENTIOMETER,
    .max_current_ma = 2000,
    .max_speed_dps = 360,
    .zero_offset1 = 0,
    .angle_min = -1350,
    .angle_max = 1350,
    .voltage_high_v = 9,
    .voltage_low_v = 6,
    .current_threshold_ma = 1500,
    .baud_min_100 = 96,
    .baud_max_100 = 10000,
    .current_max_ma = 3000,
    .speed_max_dps = 720,
    .travel_min = -1350,
    .travel_max = 1350,
    .pos_read_min = -1575,
    .pos_read_max = 1575,
    .zero_offset2_max = 100,
    .voltage_max_v = 20,
};

const km_product_t *km_board_product(void)
{
    return kf_world.pot_product ? &s_product_pot : &s_product;
}

/* The board option of km_app.h, as the test sets it. */
bool km_board_store_prepare_each_boot(void)
{
    return kf_world.prepare_each_boot;
}

/* The main loop stalls while flash is busy (kf_world.erase_us/program_us). */
static void prv_flash_stall(uint32_t us)
{
    kf_world.now += us;
    kf_world.last_idle += us; /* stalled by the hardware, not spinning */
}

static km_flash_result_t prv_flash_erase(void *ctx, uint32_t page)
{
    prv_flash_stall(kf_world.erase_us);
    return kf_world.nor_flash.erase(ctx, page);
}

static km_flash_result_t prv_flash_program(void *ctx, uint32_t offset, const void *data, uint32_t len)
{
    prv_flash_stall(kf_world.program_us * (len / kf_world.nor_flash.prog_size));
    return kf_world.nor_flash.program(ctx, offset, data, len);
}

const km_flash_t *km_board_flash(void)
{
    return &kf_world.flash;
}

/* ---- the event world ----------------------------------------------------- */

static uint32_t prv_byte_tick(uint32_t start, unsigned i)
{
    const uint32_t baud = kf_world.baud ? kf_world.baud : 115200u;
    return start + (uint32_t)(((uint64_t)i * 10u * 1000000u) / baud);
}

uint32_t kf_byte_us(void)
{
    return prv_byte_tick(0, 1);
}

static void prv_jump(int why)
{
    if (s_in_run) {
        siglongjmp(s_run_env, why);
    }
    fprintf(stderr, "fake hal: reset outside kf_run_until\n");
    abort();
}

static bool prv_due(uint32_t t)
{
    return (int32_t)(kf_world.now - t) >= 0;
}

/* Earliest pending event time; false if none. */
static bool prv_next_event(uint32_t *t)
{
    bool any = false;
    uint32_t best = 0;
#define KF_CONSIDER(x)                          \
    do {                                        \
        const uint32_t c_ = (x);                \
        if (!any || (int32_t)(c_ - best) < 0) { \
            best = c_;                          \
            any = true;                         \
        }                                       \
    } while (0)
    if (kf_world.rx_head < kf_world.rx_n) {
        KF_CONSIDER(kf_world.rx[kf_world.rx_head].tick);
    }
    if (kf_world.timer_armed) {
        KF_CONSIDER(kf_world.timer_at);
    }
    if (kf_world.tx_buf) {
        KF_CONSIDER(prv_byte_tick(kf_world.tx_start, kf_world.tx_next));
    }
    if (kf_world.wdt_running) {
        KF_CONSIDER(kf_world.wdt_last + kf_world.wdt_timeout_us + 1u);
    }
#undef KF_CONSIDER
    *t = best;
    return any;
}

/* Runs, in time order, every event whose time has come: the interrupts. */
static void prv_service(void)
{
    s_in_isr = true;
    for (;;) {
        uint32_t t;
        if (!prv_next_event(&t) || !prv_due(t)) {
            break;
        }
        if (kf_world.wdt_running && t == kf_world.wdt_last + kf_world.wdt_timeout_us + 1u) {
            kf_world.watchdog_resets++;
            kf_world.cause = KM_RESET_WATCHDOG;
            s_in_isr = false;
            prv_jump(KF_JUMP_RESET);
        }
        if (kf_world.rx_head < kf_world.rx_n && kf_world.rx[kf_world.rx_head].tick == t) {
            const kf_byte_t b = kf_world.rx[kf_world.rx_head++];
            if (kf_world.rx_handler) {
                kf_world.rx_handler(kf_world.rx_ctx, b.byte, b.tick, false);
            } /* else the servo is not listening yet: the byte is gone */
            continue;
        }
        if (kf_world.timer_armed && kf_world.timer_at == t) {
            kf_world.timer_armed = false;
            kf_world.timer_handler(kf_world.timer_ctx);
            continue;
        }
        /* TX: the next byte leaves now, read from the buffer as DMA does. */
        if (kf_world.tx_next < kf_world.tx_len) {
            if (kf_world.tx_n < KF_TX_MAX) {
                kf_world.tx[kf_world.tx_n].tick = t;
                kf_world.tx[kf_world.tx_n].byte = kf_world.tx_buf[kf_world.tx_next];
                kf_world.tx_n++;
            }
            kf_world.tx_next++;
        } else {
            kf_world.tx_buf = NULL; /* last stop bit gone: back to RX */
        }
    }
    s_in_isr = false;
}

/* Every hal call: some CPU time passes, and unmasked interrupts that came
 * due run. A main loop that has not slept for KF_SPIN_LIMIT_US of virtual
 * time is waiting on something without sleeping: a hang on a real board
 * (and, on host-sim, where timers run only while it sleeps, for ever). */
static void prv_call(void)
{
    if (s_in_isr) {
        return;
    }
    kf_world.now += kf_world.cpu_ticks_per_call;
    if (kf_world.now - kf_world.last_idle > KF_SPIN_LIMIT_US) {
        kf_world.spun = true;
        prv_jump(KF_JUMP_SPUN);
    }
    if (!kf_world.irq_masked) {
        prv_service();
    }
}

static void prv_reset_hal(void)
{
    kf_world.irq_masked = false;
    kf_world.rx_handler = NULL;
    kf_world.timer_armed = false;
    kf_world.tx_buf = NULL; /* a reset cuts a frame being sent */
    kf_world.tx_len = 0;
    kf_world.tx_next = 0;
    kf_world.wdt_running = false;
    kf_world.last_idle = kf_world.now;
    kf_world.motor_mode = 0;
    kf_world.motor_pwm = 0;
}

void kf_boot(km_reset_cause_t cause)
{
    prv_reset_hal();
    kf_world.cause = cause;
    kf_world.boots++;
    kf_world.reads_at_boot = kf_world.nor.count.reads;
    km_app_init();
    /* An emulated board: its bus floors after every start, as
     * boards/sim-common's km_sim_board_run() hands them over. */
    km_app_set_bus_floors(kf_world.gap_floor_us, kf_world.slot_floor_us);
}

void kf_power_on(void)
{
    memset(&kf_world, 0, sizeof kf_world);
    kf_world.cpu_ticks_per_call = 1;
    kf_world.voltage_mv = 7400;
    kf_world.temperature_c10 = 250;
    kf_world.now = 1000;
    const km_nor_sim_config_t cfg = {.page_size = 2048, .prog_size = 8, .page_count = 2, .fill = 0xFF};
    if (!km_nor_sim_init(&kf_world.nor, &cfg, &kf_world.nor_flash)) {
        abort();
    }
    kf_world.flash = kf_world.nor_flash;
    kf_world.flash.erase = prv_flash_erase;
    kf_world.flash.program = prv_flash_program;
    /* RAM powers up as garbage: the app's reset-surviving fault log too */
    memset(km_app_fault_log(), 0xA5, sizeof(km_fault_log_t));
    kf_boot(KM_RESET_POWER_ON);
}

void kf_send_at(uint32_t at, const uint8_t *b, unsigned n)
{
    uint32_t start = at;
    if (kf_world.rx_n > kf_world.rx_head) {
        const uint32_t after = prv_byte_tick(kf_world.rx[kf_world.rx_n - 1u].tick, 1);
        if ((int32_t)(after - start) > 0) {
            start = after;
        }
    }
    if (kf_world.rx_head == kf_world.rx_n) {
        kf_world.rx_head = kf_world.rx_n = 0;
    }
    for (unsigned i = 0; i < n && kf_world.rx_n < KF_RX_MAX; i++) {
        kf_world.rx[kf_world.rx_n].tick = prv_byte_tick(start, i);
        kf_world.rx[kf_world.rx_n].byte = b[i];
        kf_world.rx_n++;
    }
}

void kf_send_burst_at(uint32_t at, const uint8_t *b, unsigned n)
{
    if (kf_world.rx_head == kf_world.rx_n) {
        kf_world.rx_head = kf_world.rx_n = 0;
    }
    for (unsigned i = 0; i < n && kf_world.rx_n < KF_RX_MAX; i++) {
        kf_world.rx[kf_world.rx_n].tick = at;
        kf_world.rx[kf_world.rx_n].byte = b[i];
        kf_world.rx_n++;
    }
}

void kf_send_hex(const char *hex)
{
    uint8_t b[KF_RX_MAX];
    unsigned n = 0;
    for (const char *p = hex; p[0] && n < sizeof b;) {
        if (p[0] == ' ') {
            p++;
            continue;
        }
        char pair[3] = {p[0], p[1], 0};
        b[n++] = (uint8_t)strtoul(pair, NULL, 16);
        p += 2;
    }
    kf_send_at(kf_world.now, b, n);
}

/* A loop that spins on a variable without calling the hal lets no virtual
 * time pass, so only the wall clock can stop it: a test fails instead of
 * hanging CI. */
#define KF_WALL_LIMIT_S 60u

static void prv_on_alarm(int sig)
{
    (void)sig;
    kf_world.spun = true;
    siglongjmp(s_run_env, KF_JUMP_SPUN);
}

bool kf_run_until(uint32_t t)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = prv_on_alarm;
    sigaction(SIGALRM, &sa, NULL);
    for (;;) {
        s_in_run = true;
        const int why = sigsetjmp(s_run_env, 1);
        if (why == 0) {
            alarm(KF_WALL_LIMIT_S);
            while ((int32_t)(kf_world.now - t) < 0) {
                km_app_poll();
            }
            alarm(0);
            s_in_run = false;
            return true;
        }
        alarm(0);
        s_in_run = false;
        s_in_isr = false;
        if (why == KF_JUMP_SPUN) {
            return false;
        }
        kf_boot(kf_world.cause);
    }
}

bool kf_run_for(uint32_t us)
{
    return kf_run_until(kf_world.now + us);
}

unsigned kf_take_tx(uint8_t *out, unsigned cap)
{
    unsigned n = 0;
    while (kf_world.tx_read < kf_world.tx_n && n < cap) {
        out[n++] = kf_world.tx[kf_world.tx_read++].byte;
    }
    return n;
}

uint32_t kf_tx_tick(unsigned i)
{
    return kf_world.tx[i].tick;
}

/* ---- hal: system ---------------------------------------------------------- */

void km_hal_system_init(void)
{
    prv_call();
}

_Noreturn void km_hal_system_reset(void)
{
    kf_world.software_resets++;
    kf_world.cause = KM_RESET_SOFTWARE;
    prv_jump(KF_JUMP_RESET);
    abort();
}

void km_hal_watchdog_start(uint32_t timeout_ms)
{
    prv_call();
    kf_world.wdt_running = true;
    kf_world.reads_at_wdt_start = kf_world.nor.count.reads;
    kf_world.wdt_timeout_us = timeout_ms * 1000u;
    kf_world.wdt_last = kf_world.now;
}

void km_hal_watchdog_kick(void)
{
    prv_call();
    kf_world.wdt_last = kf_world.now;
}

uint32_t km_hal_irq_lock(void)
{
    prv_call();
    const uint32_t was = kf_world.irq_masked;
    kf_world.irq_masked = true;
    return was;
}

void km_hal_irq_restore(uint32_t state)
{
    kf_world.irq_masked = state != 0u;
    prv_call();
}

uint32_t km_hal_entropy(void)
{
    return 0x12345678u;
}

km_reset_cause_t km_hal_reset_cause(void)
{
    return kf_world.cause;
}

/* The board's next wake-up after `now`: 1 ms on, or the jittered SysTick's next. */
static uint32_t prv_wake_after(uint32_t now)
{
    if (kf_world.wake_late_n == 0u) {
        return now + 1000u;
    }
    for (uint32_t k = now / 1000u;; k++) {
        const uint32_t at = k * 1000u + kf_world.wake_late_us[k % kf_world.wake_late_n];
        if ((int32_t)(at - now) > 0) {
            return at;
        }
    }
}

void km_hal_idle(void)
{
    /* WFI: sleep until the next event, at most the board's wake-up. */
    uint32_t t;
    uint32_t until = prv_wake_after(kf_world.now);
    if (prv_next_event(&t) && (int32_t)(t - until) < 0) {
        until = t;
    }
    if ((int32_t)(until - kf_world.now) > 0) {
        kf_world.now = until;
    }
    kf_world.last_idle = kf_world.now;
    prv_service();
}

/* The "interrupts" run inside km_hal_idle(): it returns after each, an
 * early return the contract allows; km_hal_wake() calls are counted. */
void km_hal_sleep(uint32_t state)
{
    (void)state;
    km_hal_idle();
}

void km_hal_wake(void)
{
    kf_world.wakes++;
    kf_world.wake_at = kf_world.now;
}

/* ---- hal: time ---------------------------------------------------------- */

uint32_t km_hal_time_tick_hz(void)
{
    return KM_HAL_TICK_MHZ * 1000000u;
}

void km_hal_time_init(void)
{
    prv_call();
    kf_world.timer_armed = false;
}

uint32_t km_hal_time_now(void)
{
    prv_call();
    return kf_world.now;
}

void km_hal_timer_at(uint32_t at, km_timer_handler_t handler, void *ctx)
{
    prv_call();
    kf_world.timer_at = at;
    kf_world.timer_handler = handler;
    kf_world.timer_ctx = ctx;
    kf_world.timer_armed = true;
}

void km_hal_timer_cancel(void)
{
    prv_call(); /* a shot that came due just before the cancel still fires */
    kf_world.timer_armed = false;
}

/* ---- hal: uart ------------------------------------------------------------ */

bool km_hal_uart_init(uint32_t baud, km_uart_rx_handler_t handler, void *ctx)
{
    prv_call();
    kf_world.opens++;
    if (kf_world.unmakeable_baud && baud == kf_world.unmakeable_baud) {
        return false;
    }
    kf_world.baud = baud;
    kf_world.rx_handler = handler;
    kf_world.rx_ctx = ctx;
    return true;
}

bool km_hal_uart_send(const uint8_t *data, uint16_t len)
{
    prv_call();
    if (kf_world.tx_buf) {
        kf_world.tx_refused++;
        return false;
    }
    kf_world.tx_buf = data;
    kf_world.tx_len = len;
    kf_world.tx_next = 0;
    kf_world.tx_start = kf_world.now;
    return true;
}

bool km_hal_uart_tx_busy(void)
{
    prv_call();
    return kf_world.tx_buf != NULL;
}

/* ---- hal: motor and sensors ---------------------------------------------- */

void km_hal_motor_init(void)
{
    prv_call();
    kf_world.motor_mode = 0;
}

void km_hal_motor_drive(int16_t pwm)
{
    prv_call();
    kf_world.motor_mode = 2;
    kf_world.motor_pwm = pwm;
}

void km_hal_motor_free(void)
{
    prv_call();
    kf_world.motor_mode = 0;
    kf_world.motor_pwm = 0;
}

void km_hal_motor_brake(void)
{
    prv_call();
    kf_world.motor_brakes++;
    kf_world.motor_mode = 1;
    kf_world.motor_pwm = 0;
}

void km_hal_sensors_init(void)
{
    prv_call();
}

void kf_use_plant(int32_t pos_ddeg)
{
    if (!km_plant_init(&kf_world.plant, &km_plant_default_config)) {
        abort();
    }
    km_plant_set_position_ddeg(&kf_world.plant, pos_ddeg);
    kf_world.plant_last = kf_world.now;
    kf_world.use_plant = true;
}

/* The plant runs the bridge command in force since the last read. */
static void prv_plant_read(km_sensors_t *out)
{
    const km_plant_input_t in = {
        .bridge = kf_world.motor_mode == 2   ? KM_PLANT_DRIVE
                  : kf_world.motor_mode == 1 ? KM_PLANT_BRAKE
                                             : KM_PLANT_COAST,
        .pwm = kf_world.motor_pwm,
        .ext_torque_unm = 0,
    };
    uint32_t dt = kf_world.now - kf_world.plant_last;
    if (dt > 100000u) {
        dt = 100000u; /* as the simulated boards bound one step */
    }
    kf_world.plant_last = kf_world.now;
    km_plant_step(&kf_world.plant, &in, dt);
    out->position = km_plant_position_ddeg(&kf_world.plant);
    out->current_ma = km_plant_current_ma(&kf_world.plant);
    out->voltage_mv = km_plant_voltage_mv(&kf_world.plant);
    out->temperature_c10 = km_plant_temp_dc(&kf_world.plant);
    out->faults = kf_world.sensor_faults;
}

void km_hal_sensors_read(km_sensors_t *out)
{
    prv_call();
    if (kf_world.use_plant) {
        prv_plant_read(out);
        return;
    }
    out->position = kf_world.position;
    out->current_ma = kf_world.current_ma;
    out->voltage_mv = kf_world.voltage_mv;
    out->temperature_c10 = kf_world.temperature_c10;
    out->faults = kf_world.sensor_faults;
}
