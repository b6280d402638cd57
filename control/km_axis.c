/* SPDX-License-Identifier: Apache-2.0 */
/* The master's frame and its changes (km_axis.h); uint32 arithmetic. */
#include "km_axis.h"

km_axis_t km_axis_of(const km_control_params_t *p)
{
    const km_axis_t f = {(int32_t)p->zero_offset1 + (int32_t)p->zero_offset2, p->reverse};
    return f;
}

int32_t km_axis_map(const km_axis_t *from, const km_axis_t *to, int32_t pos)
{
    /* back to the sensor's frame, then forward into the new one */
    uint32_t sensor = from->reverse ? 0u - (uint32_t)pos : (uint32_t)pos;
    sensor -= (uint32_t)from->offset;
    const uint32_t out = sensor + (uint32_t)to->offset;
    return km_s32(to->reverse ? 0u - out : out);
}

int32_t km_axis_sign(const km_axis_t *from, const km_axis_t *to)
{
    return from->reverse == to->reverse ? 1 : -1;
}
