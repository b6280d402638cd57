/* SPDX-License-Identifier: Apache-2.0 */
/* A fake board for driving the real application (firmware/app/km_app.c)
 * on the host: every hal contract over a small discrete-event world in
 * virtual time, so a test (or a fuzz target) sends bytes on a simulated
 * wire and reads what the servo answers, with the real parser, dispatcher,
 * store (on the NOR simulator) and control glue in between.
 *
 *  - time: 1 MHz virtual ticks. Each hal call costs `cpu_ticks_per_call`
 *    ticks (default 1), the CPU time between two hal calls; km_hal_idle()
 *    jumps to the next event (byte, timer, TX end, 1 ms wake-up).
 *  - interrupts: any event whose time has come runs in "interrupt context"
 *    at the next hal call made with interrupts unmasked, or inside
 *    km_hal_idle(), as WFI would let it.
 *  - UART RX: bytes scheduled at line rate (10 bits per byte at the baud the
 *    app opened). UART TX: bytes leave the buffer one byte time apart, read
 *    from the app's buffer at that moment as DMA would (so a buffer
 *    overwritten while sending shows on the wire); busy until the last one.
 *  - reset: km_hal_system_reset() and an expired watchdog longjmp back into
 *    kf_run_until(), which boots the app again (RAM state re-initialised by
 *    km_app_init, flash kept), and record why.
 *  - sensors: fixed values a test sets, or (kf_use_plant()) the servo plant
 *    of sim/plant, advanced by the virtual time elapsed at each sensor read
 *    with the bridge command in force, as the simulated boards do; the
 *    plant is physical: it survives resets.
 *  - a main loop that does not sleep for KF_SPIN_LIMIT_US of virtual time
 *    (it sleeps at least once a control tick when it is not waiting on
 *    something) is stopped and reported through kf_world.spun. */
#ifndef KM_FAKE_HAL_H
#define KM_FAKE_HAL_H

#include <stdbool.h>
#include <stdint.h>

#include "km_hal_system.h"
#include "km_nor_sim.h"
#include "km_plant.h"

#define KF_RX_MAX 8192u
#define KF_TX_MAX 8192u
#define KF_SPIN_LIMIT_US 100000u

typedef struct {
    uint32_t tick;
    uint8_t byte;
} kf_byte_t;

typedef struct {
    /* knobs a test may set after kf_power_on() */
    uint32_t cpu_ticks_per_call;
    uint32_t gap_floor_us;  /* emulated bus floors, handed to km_app_set_bus_floors() */
    uint32_t slot_floor_us; /* at every kf_boot() */
    uint32_t unmakeable_baud;
    int32_t position, current_ma, voltage_mv, temperature_c10; /* sensors */
    uint8_t sensor_faults;
    bool pot_product; /* the board is the potentiometer product from the next kf_boot() */
    /* Flash stall (0: none): an erase or a program stops the main loop for
     * this long, as on the STM32G0 where code runs from the flash being
     * written; interrupts (RAM-resident there) come due and run after it,
     * each with its own tick, so a full RX queue drops bytes as it would. */
    uint32_t erase_us, program_us;
    bool prepare_each_boot; /* km_board_store_prepare_each_boot() */
    /* The board's wake-up from sleep: 1 ms after the sleep starts
     * (wake_late_n 0), or a free-running 1 kHz SysTick whose k-th wake-up
     * (at k ms) comes wake_late_us[k % wake_late_n] us late: jittered wake-ups. */
    const uint16_t *wake_late_us;
    unsigned wake_late_n;

    /* the world */
    uint32_t now;
    bool irq_masked;
    uint32_t baud;           /* as opened by the app */
    uint32_t opens;          /* km_hal_uart_init calls */
    kf_byte_t rx[KF_RX_MAX]; /* bytes on the wire towards the servo */
    unsigned rx_head, rx_n;
    void (*rx_handler)(void *ctx, uint8_t byte, uint32_t tick, bool lost);
    void *rx_ctx;
    kf_byte_t tx[KF_TX_MAX]; /* bytes the servo put on the wire */
    unsigned tx_n, tx_read;
    const uint8_t *tx_buf; /* the send under way */
    uint16_t tx_len, tx_next;
    uint32_t tx_start;
    uint32_t tx_refused;
    bool timer_armed;
    uint32_t timer_at;
    void (*timer_handler)(void *ctx);
    void *timer_ctx;
    uint32_t wdt_timeout_us, wdt_last;
    bool wdt_running;
    uint32_t last_idle; /* when the main loop last slept */
    unsigned wakes;     /* km_hal_wake() calls: interrupts that asked for a main-loop pass */
    uint32_t wake_at;   /* the time of the last one */
    bool spun;
    km_reset_cause_t cause; /* what km_hal_reset_cause() answers at the next boot */
    unsigned boots, software_resets, watchdog_resets;
    uint32_t reads_at_boot, reads_at_wdt_start; /* flash reads then: boot order */
    int16_t motor_pwm;
    int motor_mode;        /* 0 free, 1 brake, 2 drive */
    unsigned motor_brakes; /* km_hal_motor_brake() calls */
    km_nor_sim_t nor;
    km_flash_t nor_flash; /* the simulator's own ops */
    km_flash_t flash;     /* what the app gets: nor_flash plus the stall */
    bool use_plant;       /* sensors and motor are the plant's */
    km_plant_t plant;
    uint32_t plant_last; /* virtual time the plant was advanced to */
} kf_world_t;

extern kf_world_t kf_world;

/* Fresh world: blank flash (STM32G0 geometry), power-on, app booted. */
void kf_power_on(void);
/* From now on the sensors read the default servo plant (sim/plant), at
 * rest at `pos_ddeg`, and the motor drives it. */
void kf_use_plant(int32_t pos_ddeg);
/* Boots the app again on the same flash with `cause` as the reset cause. */
void kf_boot(km_reset_cause_t cause);

/* Puts bytes on the wire, back to back at line rate, the first at `at`
 * (or right after the last byte already queued, if that is later). */
void kf_send_at(uint32_t at, const uint8_t *b, unsigned n);
/* Bytes that reach the servo all at once at `at` (a FIFO or DMA batch, or
 * host-sim's socket): every one stamped with the same tick. */
void kf_send_burst_at(uint32_t at, const uint8_t *b, unsigned n);
/* Same as kf_send_at, from now; `hex` like "F9 FF 00 02 01 FC". */
void kf_send_hex(const char *hex);
/* Runs the app's main loop until virtual time reaches `t`, booting it again
 * after every reset. Stops early (returns false) if the loop spun. */
bool kf_run_until(uint32_t t);
bool kf_run_for(uint32_t us);

/* Frames the servo sent since the last call: copies their bytes (header to
 * checksum, concatenated) into out and returns the byte count. */
unsigned kf_take_tx(uint8_t *out, unsigned cap);
/* Tick at which the i-th byte sent since kf_power_on() left. */
uint32_t kf_tx_tick(unsigned i);

/* Byte time at the baud the app opened, in ticks (us). */
uint32_t kf_byte_us(void);

#endif
