/* SPDX-License-Identifier: Apache-2.0 */
/* This firmware's extension registers, read with 0x7F (docs/protocol.md §7; docs/protocol-decisions.md
 * "Extension command 0x7F"). */
#ifndef KM_EXT_H
#define KM_EXT_H

#define KM_CMD_EXT 0x7Fu

/* The extension command 0x7F and the fault log behind it are compiled in
 * (1, the default) or out (0: the 32 KiB STM32G031F6 build, where 0x7F is
 * an unknown command, docs/footprint.md "What gives way"). */
#ifndef KM_FEATURE_EXT
#define KM_FEATURE_EXT 1
#endif
#define KM_EXT_USERDATA_SOURCE 0x01u /* u8 KM_USERDATA_*: where the user data came from */
#define KM_EXT_RESET_CAUSE 0x02u     /* u8 km_reset_cause_t (hal/km_hal_system.h) */
#define KM_EXT_ACTIVE_BAUD 0x03u     /* u16 baud / 100 in force (0x10 may differ) */
#define KM_EXT_FAULT_SUMMARY 0x10u   /* 7 B: u32 events ever, u8 held, u8 kept from before the reset, u8 16 */
#define KM_EXT_FAULT_ENTRY 0x11u     /* 0x11 + n, n = 0 (newest) .. 15: 18 B, firmware/app/km_fault_log.h */
#define KM_EXT_FAULT_ENTRIES 16u
#define KM_EXT_VALUE_MAX 18u /* the longest extension value */

/* Extension 0x01: where the user data in force came from at boot. The
 * values follow the store's mount results. */
#define KM_USERDATA_LOADED 0u           /* from flash, as committed */
#define KM_USERDATA_MIGRATED 1u         /* from flash; registers new to this firmware at defaults */
#define KM_USERDATA_DEFAULTS_BLANK 2u   /* product defaults: flash erased (first boot) */
#define KM_USERDATA_DEFAULTS_INVALID 3u /* product defaults: no valid record in flash */
#define KM_USERDATA_DEFAULTS_SCHEMA 4u  /* product defaults: stored layout from another version */
#define KM_USERDATA_UNAVAILABLE 5u      /* store unusable: defaults, commits fail (bit 6) */

#endif
