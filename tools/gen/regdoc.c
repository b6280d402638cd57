/* SPDX-License-Identifier: Apache-2.0 */
/* Prints docs/registers.md from the register table (protocol/km_registers.def
 * and its units and descriptions, km_registers_doc.def) so the document cannot
 * drift from the code: CTest (tests/regdoc.cmake) diffs this output against
 * the checked-in file. With --json it prints docs/registers.json instead, the
 * machine-readable description host tools load (tools/gen/regdoc_json.c).
 *
 *   build/host/tests/km_regdoc > docs/registers.md
 *   build/host/tests/km_regdoc --json > docs/registers.json
 *
 * A default that changes with the product config is printed as "product":
 * it is detected by asking the table for the default under two product
 * configs that differ in every field. */
#include <stdio.h>
#include <string.h>

#include "regdoc.h"

const km_product_t regdoc_probe_a = {
    .model = "A",
    .firmware_version = 0x11111111u,
    .variant = KM_VARIANT_POTENTIOMETER,
    .max_current_ma = 1001,
    .max_speed_dps = 101,
    .zero_offset1 = 11,
    .angle_min = -11,
    .angle_max = 11,
    .voltage_high_v = 21,
    .voltage_low_v = 1,
    .current_threshold_ma = 901,
    .baud_min_100 = 91,
    .baud_max_100 = 9001,
    .current_max_ma = 2001,
    .speed_max_dps = 201,
    .travel_min = -21,
    .travel_max = 21,
    .zero_offset2_max = 31,
    .voltage_max_v = 31,
};

const km_product_t regdoc_probe_b = {
    .model = "B",
    .firmware_version = 0x22222222u,
    .variant = KM_VARIANT_ENCODER,
    .max_current_ma = 1002,
    .max_speed_dps = 102,
    .zero_offset1 = 12,
    .angle_min = -12,
    .angle_max = 12,
    .voltage_high_v = 22,
    .voltage_low_v = 2,
    .current_threshold_ma = 902,
    .baud_min_100 = 92,
    .baud_max_100 = 9002,
    .current_max_ma = 2002,
    .speed_max_dps = 202,
    .travel_min = -22,
    .travel_max = 22,
    .zero_offset2_max = 32,
    .voltage_max_v = 32,
};

const char *regdoc_access_name(uint8_t a)
{
    return a == KM_RW ? "RW" : (a == KM_R ? "R" : "W");
}

static const char *layout_name(uint8_t l)
{
    switch ((km_layout_t)l) {
    case KM_L_U8:
        return "u8";
    case KM_L_BITS8:
        return "u8 bits";
    case KM_L_I8:
        return "i8";
    case KM_L_U16:
        return "u16";
    case KM_L_I16:
        return "i16";
    case KM_L_U32:
        return "u32";
    case KM_L_U8U8:
        return "u8, u8";
    case KM_L_U16U8:
        return "u16, u8";
    case KM_L_STATUS:
        return "u8 status, u8 random";
    case KM_L_MAGIC:
        return "E1 E2 E3 E4";
    case KM_L_TEXT:
        return "ASCII, up to 16 B";
    case KM_L_POS:
        return "i16 or i32";
    case KM_L_MOVE:
        return "i16 [, u16]";
    case KM_L_ADV:
        return "u8, 16 bit, 16 bit";
    }
    return "?";
}

/* Stored values only: registers that are written and read back, or user data. */
int regdoc_has_stored_default(const km_reg_t *r)
{
    const km_layout_t l = (km_layout_t)r->layout;
    const int value_layout = l == KM_L_U8 || l == KM_L_BITS8 || l == KM_L_I8 || l == KM_L_U16 ||
                             l == KM_L_I16 || l == KM_L_U8U8 || l == KM_L_U16U8;
    return value_layout && (r->access == KM_RW || r->persisted);
}

static void print_default(const km_reg_t *r, uint32_t v)
{
    switch ((km_layout_t)r->layout) {
    case KM_L_U8: /* bit fields read best in hex (0x11, 0x32..0x34) */
    case KM_L_BITS8:
        printf("0x%02X", (unsigned)v);
        break;
    case KM_L_I8:
        printf("%d", (int)(int8_t)v);
        break;
    case KM_L_I16:
        printf("%d", (int)(int16_t)v);
        break;
    case KM_L_U8U8:
        printf("%u, %u", (unsigned)(v & 0xFFu), (unsigned)((v >> 8) & 0xFFu));
        break;
    case KM_L_U16U8:
        printf("%u, %u", (unsigned)(v & 0xFFFFu), (unsigned)((v >> 16) & 0xFFu));
        break;
    default:
        printf("%u", (unsigned)v);
        break;
    }
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "--json") == 0) {
        return regdoc_json();
    }
    if (argc != 1) {
        fprintf(stderr, "usage: %s [--json]\n", argv[0]);
        return 2;
    }
    printf("# Register table\n\n");
    printf("Generated from `protocol/km_registers.def` by `tools/gen/regdoc.c`; do not edit.\n");
    printf("Regenerate with `build/host/tests/km_regdoc > docs/registers.md`\n");
    printf("(CTest `regdoc_up_to_date` fails when this file is out of date).\n\n");
    printf("Access: R read, W write. P = persisted user data. Default: stored registers\n");
    printf("only; \"product\" = taken from the product config (`km_product.h`), \"—\" =\n");
    printf("computed, live or an action. Multi-byte values are little-endian; two-field\n");
    printf("defaults are listed field by field. Unit: value = wire value x unit (\"0.1 °\":\n");
    printf("450 reads 45.0°); blank = a plain number, bit field or bytes. The same table,\n");
    printf("with ranges and descriptions, for tools: `docs/registers.json` (`km_regdoc --json`).\n\n");
    printf("| adr | name | access | P | layout | default | unit |\n");
    printf("|---|---|---|---|---|---|---|\n");
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        const km_reg_t *r = &km_reg_table[i];
        printf("| 0x%02X | %s | %s | %s | %s | ", r->addr, km_reg_names[i], regdoc_access_name(r->access),
               r->persisted ? "P" : "", layout_name(r->layout));
        if (!regdoc_has_stored_default(r)) {
            printf("—");
        } else {
            const uint32_t a = km_reg_default((km_reg_index_t)i, &regdoc_probe_a);
            const uint32_t b = km_reg_default((km_reg_index_t)i, &regdoc_probe_b);
            if (a != b) {
                printf("product");
            } else {
                print_default(r, a);
            }
        }
        char unit[32], unit2[32];
        regdoc_unit_text(unit, sizeof unit, regdoc_docs[i].unit, regdoc_docs[i].scale);
        regdoc_unit_text(unit2, sizeof unit2, regdoc_docs[i].unit2, regdoc_docs[i].scale2);
        printf(" | %s%s%s |\n", unit, unit2[0] != '\0' ? ", " : "", unit2);
    }
    return 0;
}
