/* SPDX-License-Identifier: Apache-2.0 */
/* The register table (docs/protocol.md §5) generated from km_registers.def; values are wire bytes packed LE
 * in a u32. */
#ifndef KM_REGISTERS_H
#define KM_REGISTERS_H

#include <stdbool.h>
#include <stdint.h>

#include "km_params.h" /* KM_MODE_LAST, KM_FEATURE_MOTOR_MODE: the .def's bounds and rows */
#include "km_product.h"

/* KM_GONE: a register this build leaves out (km_registers.def): no read,
 * no write, no 0x83; every command answers it as a reserved address. */
typedef enum { KM_GONE = 0, KM_R = 1, KM_W = 2, KM_RW = 3 } km_access_t;

typedef enum {
    KM_L_U8,     /* 1 B */
    KM_L_BITS8,  /* 1 B bit field: bits above `max` are reserved, ignored on write, read 0 */
    KM_L_I8,     /* 1 B */
    KM_L_U16,    /* 2 B */
    KM_L_I16,    /* 2 B */
    KM_L_U32,    /* 4 B */
    KM_L_U8U8,   /* 2 B: two u8 fields */
    KM_L_U16U8,  /* 3 B: u16 then u8 */
    KM_L_STATUS, /* read: status, random */
    KM_L_MAGIC,  /* write: exactly E1 E2 E3 E4 */
    KM_L_TEXT,   /* read: ASCII model name, up to 16 B */
    KM_L_POS,    /* i16, or i32 when the value does not fit (length tells) */
    KM_L_MOVE,   /* write: i16 target [, u16 time or speed] */
    KM_L_ADV,    /* write: u8 control byte, then two 16-bit parameters */
} km_layout_t;

typedef enum {
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi, multi, rd, wr) KM_REG_##ident,
#include "km_registers.def"
#undef KM_REG
    KM_REG_COUNT
} km_reg_index_t;

/* How many registers are user data (P), at compile time, to size arrays. */
enum {
    KM_REG_PERSISTED_COUNT = 0
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi, multi, rd, wr) \
    +(persisted) // NOLINT(bugprone-macro-parentheses)
#include "km_registers.def"
#undef KM_REG
};

/* 0x83 multi-ID write: the parameter sizes a register takes, one bit each
 * (the .def's `multi` column; 0 = not multi-writable). */
#define KM_K(n) (1u << (n))

/* Three bytes a row: access, persisted and layout share one. */
typedef struct {
    uint8_t addr;
    uint8_t layout : 5;    /* km_layout_t */
    uint8_t access : 2;    /* km_access_t */
    uint8_t persisted : 1; /* 1 = user data */
    uint8_t multi;         /* KM_K() bits: sizes an 0x83 entry may have, 0 = none */
} km_reg_t;

extern const km_reg_t km_reg_table[KM_REG_COUNT];

/* The register's name as the .def spells it (tools and tests; the
 * firmware does not link it). */
extern const char *const km_reg_names[KM_REG_COUNT];

/* KM_PROTOCOL_COMPACT=1 (the 32 KiB STM32G031F6 build, docs/footprint.md): the smaller, slower forms of the
 * protocol code (the parser's batch entry byte by byte, the register look-up by a search). */
#ifndef KM_PROTOCOL_COMPACT
#define KM_PROTOCOL_COMPACT 0
#endif

#define KM_REG_ADDR_SPAN 128u
#if KM_PROTOCOL_COMPACT
/* Table index of an address, or -1 for a reserved/unknown address: a binary search of km_reg_table (in
 * address order, as km_registers.def lists it). */
int km_reg_find(uint8_t addr);
#else
/* Register index + 1 by address, 0 where there is none. */
extern const uint8_t km_reg_by_addr[KM_REG_ADDR_SPAN];

/* Table index of an address, or -1 for a reserved/unknown address: one
 * load (every read and write looks one up). */
static inline int km_reg_find(uint8_t addr)
{
    return addr < KM_REG_ADDR_SPAN ? (int)km_reg_by_addr[addr] - 1 : -1;
}
#endif

uint32_t km_reg_default(km_reg_index_t reg, const km_product_t *p);

/* Checks the bytes of a write: length for the layout, every field in range,
 * cross-field rules. On success stores the packed value in *packed. */
bool km_reg_validate(km_reg_index_t reg, const km_product_t *p, const uint8_t *data, uint8_t len,
                     uint32_t *packed);

/* Bytes a stored value takes on the wire for fixed layouts (0 otherwise). */
uint8_t km_reg_fixed_size(km_layout_t layout);

/* The same, inline, so that a constant layout folds at compile time. */
static inline uint8_t km_reg_fixed_size_const(km_layout_t layout)
{
    switch (layout) {
    case KM_L_U8:
    case KM_L_BITS8:
    case KM_L_I8:
        return 1;
    case KM_L_U16:
    case KM_L_I16:
    case KM_L_U8U8:
    case KM_L_STATUS:
        return 2;
    case KM_L_U16U8:
        return 3;
    case KM_L_U32:
    case KM_L_MAGIC:
        return 4;
    default:
        return 0;
    }
}

/* Encodes a value little-endian into out; returns the byte count. */
uint8_t km_put_le(uint8_t *out, uint32_t value, uint8_t size);

/* Reads n (1..4) little-endian bytes. */
uint32_t km_get_le(const uint8_t *in, uint8_t n);

#endif
