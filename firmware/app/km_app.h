/* SPDX-License-Identifier: Apache-2.0 */
/* The firmware application, the same on every board: hal -> receive queue ->
 * parser -> dispatcher -> answer timer -> hal; the user-data store; the fixed
 * control tick. A board's main() prepares its hal and calls km_app_run(). */
#ifndef KM_APP_H
#define KM_APP_H

#include "km_fault_log.h"
#include "km_hal_flash.h"
#include "km_product.h"
#include "km_servo.h"

/* Provided by the board: its product config and its user-data flash region. */
const km_product_t *km_board_product(void);
const km_flash_t *km_board_flash(void);

/* Measurement hook (weak, empty by default): see km_app.c. */
void km_app_answer_started(uint32_t frame_end, uint32_t started, uint32_t delay_us);

/* Initialises everything and runs the main loop; never returns. It is
 * km_app_init() then km_app_poll() for ever; the two are separate so a host
 * test can drive the real loop one pass at a time over a fake hal. */
_Noreturn void km_app_run(void);

/* A board with a bootloader (docs/update.md) defines this: leave the
 * "stay in update mode" request for it, with the ID and baud the servo
 * answers on (update mode answers there, §3), and return true; the app
 * then restarts. The app's weak default returns false (no bootloader:
 * 0x78 ENTER is refused with bit 5). */
bool km_board_boot_request(uint8_t id, uint32_t baud);

/* A board with a bootloader defines this (docs/update.md §3a): the app
 * calls it once per boot, after its main loop has served the bus for 1 s,
 * to confirm the start to the bootloader's trial. Weak default: nothing. */
void km_board_boot_confirm(void);

/* A board that wants the store prepared in idle time in every session,
 * not only when it needs formatting, defines this to return true: the
 * session's first saved setting then never waits on an erase, at the cost
 * of one erase per boot (docs/store.md "Preparing in idle time"). Weak
 * default: false. */
bool km_board_store_prepare_each_boot(void);

/* Boot: hal, store mount, dispatcher, control, bus. Resets every piece of
 * the app's state, so a test may call it again to model a reset. */
void km_app_init(void);

/* Emulated buses only: the floors their delivery needs, which a real UART
 * never does (docs/architecture.md "Boards and the build"). gap_floor_us:
 * the least silence inside a frame that drops it, when longer than the
 * parser's rule (docs/protocol-decisions.md "Inter-byte gap"); an emulator
 * that hands bytes over when the host schedules it can stall inside a
 * frame. slot_floor_us: the least super-ID / 0x82 answer slot ("Answer
 * slots on emulated buses"). km_app_init() sets both back to 0, the real
 * rules, so a simulated board calls this after every km_app_init() and
 * before the first km_app_poll(). A real board never calls it. */
void km_app_set_bus_floors(uint32_t gap_floor_us, uint32_t slot_floor_us);

/* One pass of the main loop: report the last answer's timing, hand a
 * waiting answer to TX, parse up to 64 received bytes, restart if one is
 * due and nothing is left to send, run the control tick when due, else
 * compact the store or sleep in km_hal_idle(). Never waits on the bus. */
void km_app_poll(void);

/* Answers the UART refused to start (0 unless a board breaks its contract). */
uint32_t km_app_tx_refused(void);

/* The servo's register file and status, read-only, for host tests and the
 * fuzz target's invariants (and a debugger). */
const km_servo_t *km_app_servo(void);

/* The fault log's RAM (kept across resets, km_fault_log.h): a test board
 * fills it with power-up garbage at a simulated power-on. */
km_fault_log_t *km_app_fault_log(void);

#endif
