/* SPDX-License-Identifier: Apache-2.0 */
/* Shared by the register-document generators (tools/gen/regdoc.c writes
 * docs/registers.md, tools/gen/regdoc_json.c docs/registers.json): the two probe
 * product configs that tell a product-dependent value from a fixed one, and
 * the names of access modes and wire layouts. */
#ifndef REGDOC_H
#define REGDOC_H

#include "km_registers.h"

/* Two product configs that differ in every field: a default or bound that
 * differs between them comes from the product config ("product"). */
extern const km_product_t regdoc_probe_a;
extern const km_product_t regdoc_probe_b;

const char *regdoc_access_name(uint8_t access);

/* One row of protocol/km_registers_doc.def, indexed like km_reg_table. */
typedef struct {
    const char *title;
    const char *unit; /* first value field: value in unit = wire value * scale */
    double scale;
    const char *unit2; /* second field of two-field layouts, else "" */
    double scale2;
    const char *description;
} regdoc_doc_t;

extern const regdoc_doc_t regdoc_docs[KM_REG_COUNT];

/* Writes "unit" or "scale unit" of one field ("" for a plain number) into
 * buf, e.g. "0.1 °", "mA". */
void regdoc_unit_text(char *buf, unsigned size, const char *unit, double scale);

/* Stored values only: registers that are written and read back, or user data. */
int regdoc_has_stored_default(const km_reg_t *r);

/* Prints docs/registers.json; returns the exit status (1 when the doc table
 * km_registers_doc.def leaves a register without a title). */
int regdoc_json(void);

#endif
