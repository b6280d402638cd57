/* SPDX-License-Identifier: Apache-2.0 */
/* The units, scales and descriptions of protocol/km_registers_doc.def as a
 * table indexed like km_reg_table, checked at compile time to name every
 * register of km_registers.def exactly once: each row is a designated
 * initializer [KM_REG_<ident>] (an unknown name does not compile, a repeated
 * one trips -Woverride-init under -Werror) and the counts must agree. */
#include <stdio.h>

#include "regdoc.h"

enum {
    REGDOC_DOC_COUNT = 0
#define KM_REG_DOC(ident, title, unit, scale, unit2, scale2, desc) +1
#include "km_registers_doc.def"
#undef KM_REG_DOC
};

_Static_assert((int)REGDOC_DOC_COUNT == (int)KM_REG_COUNT,
               "km_registers_doc.def must describe every register of km_registers.def once");

const regdoc_doc_t regdoc_docs[KM_REG_COUNT] = {
#define KM_REG_DOC(ident, title, unit, scale, unit2, scale2, desc) \
    [KM_REG_##ident] = {title, unit, scale, unit2, scale2, desc},
#include "km_registers_doc.def"
#undef KM_REG_DOC
};

void regdoc_unit_text(char *buf, unsigned size, const char *unit, double scale)
{
    if (unit[0] == '\0') {
        snprintf(buf, size, "%s", "");
    } else if (scale == 1.0) {
        snprintf(buf, size, "%s", unit);
    } else {
        snprintf(buf, size, "%g %s", scale, unit);
    }
}
