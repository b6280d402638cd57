/* SPDX-License-Identifier: Apache-2.0 */
/* The registers' names, for tools and tests (tools/gen/regdoc.c prints them):
 * in a file of their own, so the firmware, which never names a register,
 * does not carry the strings. */
#include "km_registers.h"

const char *const km_reg_names[KM_REG_COUNT] = {
#define KM_REG(addr, ident, access, persisted, layout, def, lo, hi, multi, rd, wr) #ident,
#include "km_registers.def"
#undef KM_REG
};
