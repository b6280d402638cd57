/* SPDX-License-Identifier: Apache-2.0 */
/* The master's frame (docs/protocol.md §5.1): position = (sensor + 0x16 +
 * 0x17), negated when 0x11 bit 2 is set; a frame change maps control's
 * state so the shaft does not move. docs/control-design.md. */
#ifndef KM_AXIS_H
#define KM_AXIS_H

#include <stdbool.h>
#include <stdint.h>

#include "km_params.h"

typedef struct {
    int32_t offset; /* 0x16 + 0x17, 0.1 deg */
    bool reverse;   /* 0x11 bit 2 */
} km_axis_t;

/* uint32 to int32 modulo 2^32 (implementation-defined in C11 6.3.1.3;
 * GCC and Clang define it so). */
static inline int32_t km_s32(uint32_t u)
{
    return (int32_t)u;
}

/* a - b on positions, modular: the short way round across the int32 wrap. */
static inline int32_t km_pos_diff(int32_t a, int32_t b)
{
    return km_s32((uint32_t)a - (uint32_t)b);
}

/* a + b on positions, modular like km_pos_diff. */
static inline int32_t km_pos_add(int32_t a, int32_t b)
{
    return km_s32((uint32_t)a + (uint32_t)b);
}

/* A sensor reading as a master position in frame `a`. */
static inline int32_t km_axis_position(const km_axis_t *a, int32_t sensor)
{
    const uint32_t pos = (uint32_t)sensor + (uint32_t)a->offset;
    return km_s32(a->reverse ? 0u - pos : pos);
}

/* True when `a` is not the frame `p` describes. */
static inline bool km_axis_differs(const km_axis_t *a, const km_control_params_t *p)
{
    return a->offset != (int32_t)p->zero_offset1 + (int32_t)p->zero_offset2 || a->reverse != p->reverse;
}

/* The frame `p` describes. */
km_axis_t km_axis_of(const km_control_params_t *p);

/* A position of frame `from` in frame `to` (the same shaft angle). */
int32_t km_axis_map(const km_axis_t *from, const km_axis_t *to, int32_t pos);

/* -1 when the two frames count in opposite directions, else 1. */
int32_t km_axis_sign(const km_axis_t *from, const km_axis_t *to);

/* The product travel in the master's frame of `p`: [*lo, *hi]. */
static inline void km_axis_travel(const km_control_params_t *p, int32_t *lo, int32_t *hi)
{
    const int32_t off = (int32_t)p->zero_offset1 + (int32_t)p->zero_offset2;
    const int32_t a = (int32_t)p->travel_min + off;
    const int32_t b = (int32_t)p->travel_max + off;
    *lo = p->reverse ? -b : a;
    *hi = p->reverse ? -a : b;
}

#endif
