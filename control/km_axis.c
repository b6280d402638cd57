/* SPDX-License-Identifier: Apache-2.0 */
/* The master's frame and its changes (see km_axis.h). Arithmetic on
 * positions is done in uint32 and converted back: a defined two's
 * complement wrap, like the multi-turn count's (docs/protocol-decisions.md
 * "Multi-turn position and its wrap"). */
#include "km_axis.h"

/* A uint32 back to int32 without implementation-defined conversion. */
static int32_t prv_s32(uint32_t u)
{
    return u <= 0x7FFFFFFFu ? (int32_t)u : -(int32_t)(~u) - 1;
}

int32_t km_axis_position(const km_axis_t *a, int32_t sensor)
{
    const uint32_t pos = (uint32_t)sensor + (uint32_t)a->offset;
    return prv_s32(a->reverse ? 0u - pos : pos);
}

km_axis_t km_axis_of(const km_control_params_t *p)
{
    const km_axis_t f = {(int32_t)p->zero_offset1 + (int32_t)p->zero_offset2, p->reverse};
    return f;
}

bool km_axis_changed(const km_axis_t *a, const km_axis_t *b)
{
    return a->offset != b->offset || a->reverse != b->reverse;
}

int32_t km_axis_map(const km_axis_t *from, const km_axis_t *to, int32_t pos)
{
    /* back to the sensor's frame, then forward into the new one */
    uint32_t sensor = from->reverse ? 0u - (uint32_t)pos : (uint32_t)pos;
    sensor -= (uint32_t)from->offset;
    const uint32_t out = sensor + (uint32_t)to->offset;
    return prv_s32(to->reverse ? 0u - out : out);
}

int32_t km_axis_sign(const km_axis_t *from, const km_axis_t *to)
{
    return from->reverse == to->reverse ? 1 : -1;
}

void km_axis_travel(const km_control_params_t *p, int32_t *lo, int32_t *hi)
{
    const int32_t off = (int32_t)p->zero_offset1 + (int32_t)p->zero_offset2;
    const int32_t a = (int32_t)p->travel_min + off;
    const int32_t b = (int32_t)p->travel_max + off;
    *lo = p->reverse ? -b : a;
    *hi = p->reverse ? -a : b;
}
