/* SPDX-License-Identifier: Apache-2.0 */
/* The bits protocol and control share (docs/protocol.md §4, §5.2). */
#ifndef KM_STATUS_H
#define KM_STATUS_H

/* Status byte bits (§4). */
#define KM_ST_RUNNING 0x80u
#define KM_ST_FAILED 0x40u
#define KM_ST_EXCEPTION 0x20u
#define KM_ST_HW_FAULT 0x10u
#define KM_ST_PROTECTION 0x0Fu /* stall, temperature, current, voltage */

/* Protections: 0x32/0x33/0x36 bits, status bits 0..3. */
#define KM_PROT_VOLTAGE 0x01u
#define KM_PROT_CURRENT 0x02u
#define KM_PROT_TEMPERATURE 0x04u
#define KM_PROT_STALL 0x08u
#define KM_PROT_ALL 0x0Fu

/* Hardware faults: 0x35 bits. */
#define KM_HW_CRYSTAL 0x01u
#define KM_HW_MEMORY 0x02u
#define KM_HW_TEMPERATURE 0x04u
#define KM_HW_VOLTAGE 0x08u
#define KM_HW_CURRENT 0x10u
#define KM_HW_POSITION 0x20u
#define KM_HW_MOTOR 0x40u
#define KM_HW_OTHER 0x80u

#endif
