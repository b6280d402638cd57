/* SPDX-License-Identifier: Apache-2.0 */
/* Prints docs/registers.json (`km_regdoc --json`): the register map of
 * docs/protocol.md §5 for host tools (host/kmx/registers.py), from the firmware's
 * own table (protocol/km_registers.def: address, access, persistence, wire
 * layout, default, range) and its units and descriptions
 * (km_registers_doc.def). A default or range bound that comes from the
 * product config is printed as "product": the host cannot know the product,
 * the servo checks it. Ranges are those of the firmware's write check: the
 * first field (both fields of a u8,u8 layout); cross-field rules stay with
 * the servo. */
#include <stdio.h>

#include "km_registers_range.h"
#include "regdoc.h"

typedef struct {
    const char *key;       /* layout identifier in the JSON */
    const char *type;      /* wire types, as in docs/registers.md */
    const char *fields[3]; /* type of each value field */
    const char *lengths;   /* the allowed lengths, a JSON array */
} layout_info_t;

static const layout_info_t s_layouts[] = {
    [KM_L_U8] = {"u8", "u8", {"u8"}, "[1]"},
    [KM_L_BITS8] = {"bits8", "u8 bits", {"bits8"}, "[1]"},
    [KM_L_I8] = {"i8", "i8", {"i8"}, "[1]"},
    [KM_L_U16] = {"u16", "u16", {"u16"}, "[2]"},
    [KM_L_I16] = {"i16", "i16", {"i16"}, "[2]"},
    [KM_L_U32] = {"u32", "u32", {"u32"}, "[4]"},
    [KM_L_U8U8] = {"u8u8", "u8, u8", {"u8", "u8"}, "[2]"},
    [KM_L_U16U8] = {"u16u8", "u16, u8", {"u16", "u8"}, "[3]"},
    [KM_L_STATUS] = {"status", "u8 status, u8 random", {"bits8", "u8"}, "[2]"},
    [KM_L_MAGIC] = {"magic", "E1 E2 E3 E4", {"bytes"}, "[4]"},
    [KM_L_TEXT] = {"text",
                   "ASCII, up to 16 B",
                   {"ascii"},
                   "[1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16]"},
    [KM_L_POS] = {"pos", "i16 or i32", {"i16/i32"}, "[2, 4]"},
    [KM_L_MOVE] = {"move", "i16 [, u16]", {"i16", "u16"}, "[2, 4]"},
    [KM_L_ADV] = {"adv", "u8, 16 bit, 16 bit", {"u8", "x16", "x16"}, "[5]"},
};

_Static_assert(sizeof s_layouts / sizeof s_layouts[0] == (unsigned)KM_L_ADV + 1u,
               "every layout of km_registers.h needs a row here");

static void print_string(const char *s)
{
    putchar('"');
    for (; *s != '\0'; s++) {
        if (*s == '"' || *s == '\\') {
            putchar('\\');
        }
        putchar(*s);
    }
    putchar('"');
}

static void print_bound(long a, long b)
{
    if (a != b) {
        printf("\"product\"");
    } else {
        printf("%ld", a);
    }
}

/* One default field of the packed wire value, as the number it means. */
static long field_value(const char *type, uint32_t v)
{
    if (type[0] == 'i' && type[1] == '8') {
        return (long)(int8_t)(v & 0xFFu);
    }
    if (type[0] == 'i') {
        return (long)(int16_t)(v & 0xFFFFu);
    }
    return (long)v;
}

static void print_default(unsigned i, const layout_info_t *li)
{
    const km_reg_t *r = &km_reg_table[i];
    if (!regdoc_has_stored_default(r)) {
        printf("null");
        return;
    }
    const uint32_t a = km_reg_default((km_reg_index_t)i, &regdoc_probe_a);
    const uint32_t b = km_reg_default((km_reg_index_t)i, &regdoc_probe_b);
    if (a != b) {
        printf("\"product\"");
    } else if (r->layout == KM_L_U8U8) {
        printf("[%lu, %lu]", (unsigned long)(a & 0xFFu), (unsigned long)((a >> 8) & 0xFFu));
    } else if (r->layout == KM_L_U16U8) {
        printf("[%lu, %lu]", (unsigned long)(a & 0xFFFFu), (unsigned long)((a >> 16) & 0xFFu));
    } else {
        printf("%ld", field_value(li->fields[0], a));
    }
}

static int value_layout(uint8_t layout)
{
    switch ((km_layout_t)layout) {
    case KM_L_U8:
    case KM_L_I8:
    case KM_L_U16:
    case KM_L_I16:
    case KM_L_U8U8:
    case KM_L_U16U8:
    case KM_L_MOVE:
        return 1;
    default:
        return 0;
    }
}

static void print_field(unsigned i, unsigned f, const layout_info_t *li)
{
    const km_reg_t *r = &km_reg_table[i];
    const regdoc_doc_t *d = &regdoc_docs[i];
    const int second =
        f == 1u && (r->layout == KM_L_U8U8 || r->layout == KM_L_U16U8 || r->layout == KM_L_MOVE);
    const char *unit = second ? d->unit2 : (f == 0u ? d->unit : "");
    const double scale = second ? d->scale2 : (f == 0u ? d->scale : 1.0);
    printf("{\"type\": \"%s\", \"unit\": ", li->fields[f]);
    print_string(unit);
    printf(", \"scale\": %.10g", scale);
    const int writable = (r->access & KM_W) != 0;
    int32_t lo_a, hi_a, lo_b, hi_b;
    km_reg_range((km_reg_index_t)i, &regdoc_probe_a, &lo_a, &hi_a);
    km_reg_range((km_reg_index_t)i, &regdoc_probe_b, &lo_b, &hi_b);
    if (writable && r->layout == KM_L_BITS8) {
        printf(", \"mask\": %ld", (long)hi_a);
    } else if (writable && value_layout(r->layout) && (f == 0u || r->layout == KM_L_U8U8)) {
        printf(", \"min\": ");
        print_bound(lo_a, lo_b);
        printf(", \"max\": ");
        print_bound(hi_a, hi_b);
    }
    if (f == 1u && r->layout == KM_L_MOVE) {
        printf(", \"optional\": true");
    }
    printf("}");
}

int regdoc_json(void)
{
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        const regdoc_doc_t *d = &regdoc_docs[i];
        if (d->title == NULL || d->description == NULL || d->scale == 0.0) {
            fprintf(stderr, "km_registers_doc.def: no row for %s\n", km_reg_names[i]);
            return 1;
        }
    }
    printf("{\n");
    printf("  \"comment\": \"Generated from protocol/km_registers.def and km_registers_doc.def by "
           "tools/gen/regdoc_json.c (km_regdoc --json); do not edit. Value in unit = wire value * scale; "
           "\\\"product\\\" = taken from the product config; ranges are the firmware's write check "
           "of the first field (both fields of u8u8).\",\n");
    printf("  \"protocol\": \"KINGMAX serial servo protocol v5.2.0, docs/protocol.md section 5\",\n");
    printf("  \"registers\": [\n");
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        const km_reg_t *r = &km_reg_table[i];
        const regdoc_doc_t *d = &regdoc_docs[i];
        const layout_info_t *li = &s_layouts[r->layout];
        char name[32];
        unsigned n = 0;
        for (const char *c = km_reg_names[i]; *c != '\0' && n + 1u < sizeof name; c++, n++) {
            name[n] = (char)(*c >= 'A' && *c <= 'Z' ? *c - 'A' + 'a' : *c);
        }
        name[n] = '\0';
        printf("    {\"address\": %u, \"hex\": \"0x%02X\", \"name\": \"%s\", \"title\": ", r->addr, r->addr,
               name);
        print_string(d->title);
        printf(",\n     \"access\": \"%s\", \"persisted\": %s, \"layout\": \"%s\", \"type\": \"%s\", "
               "\"lengths\": %s,\n     \"default\": ",
               regdoc_access_name(r->access), r->persisted ? "true" : "false", li->key, li->type,
               li->lengths);
        print_default(i, li);
        printf(",\n     \"fields\": [");
        for (unsigned f = 0; f < 3u && li->fields[f] != NULL; f++) {
            printf(f > 0u ? ", " : "");
            print_field(i, f, li);
        }
        printf("],\n     \"description\": ");
        print_string(d->description);
        printf("}%s\n", i + 1u < KM_REG_COUNT ? "," : "");
    }
    printf("  ]\n}\n");
    return 0;
}
