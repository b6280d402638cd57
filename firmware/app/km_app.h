/* SPDX-License-Identifier: Apache-2.0 */
/* The firmware application, the same on every board: hal -> receive queue ->
 * parser -> dispatcher -> answer timer -> hal; the user-data store; the
 * control tick (docs/app-design.md). */
#ifndef KM_APP_H
#define KM_APP_H

#include "km_fault_log.h"
#include "km_hal_flash.h"
#include "km_product.h"
#include "km_servo.h"

/* Provided by the board: its product config and its user-data flash region. */
const km_product_t *km_board_product(void);
const km_flash_t *km_board_flash(void);

/* Measurement hook (weak, empty): each answer's frame end, start and delay. */
void km_app_answer_started(uint32_t frame_end, uint32_t started, uint32_t delay_us);

/* km_app_init() then km_app_poll() for ever. */
_Noreturn void km_app_run(void);

/* A board with a bootloader leaves it the update-mode request (ID, baud;
 * docs/update.md, docs/protocol.md §3) and returns true; weak default false. */
bool km_board_boot_request(uint8_t id, uint32_t baud);

/* Confirms the start to the bootloader's trial, once per boot after 1 s of
 * service (docs/update.md §3a). Weak default: nothing. */
void km_board_boot_confirm(void);

/* True: prepare the store in idle time every session, not only when it
 * needs formatting (docs/store.md "Preparing in idle time"). Weak: false. */
bool km_board_store_prepare_each_boot(void);

/* Boot: hal, store mount, dispatcher, control, bus; resets all app state. */
void km_app_init(void);

/* Emulated buses only, after every km_app_init(): the least inter-byte gap
 * and answer slot their delivery needs (docs/app-design.md). */
void km_app_set_bus_floors(uint32_t gap_floor_us, uint32_t slot_floor_us);

/* One pass of the main loop; never waits on the bus. */
void km_app_poll(void);

/* Answers the UART refused to start (0 unless a board breaks its contract). */
uint32_t km_app_tx_refused(void);

/* The servo's register file and status, read-only (tests, fuzzing). */
const km_servo_t *km_app_servo(void);

/* The fault log's RAM, kept across resets (a test board fills it with garbage). */
km_fault_log_t *km_app_fault_log(void);

#endif
