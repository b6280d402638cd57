/* SPDX-License-Identifier: Apache-2.0 */
/* libFuzzer target for the user-data store as the firmware boots on it:
 * firmware/store mounted through the app's path (km_app_userdata_mount(),
 * the product's schema of persisted registers, docs/protocol.md §5) on the NOR
 * simulator, over flash images the input builds, breaks and rewrites; the
 * values then go into the register file (km_servo_init) and every register
 * is read back with a §2 read frame (km_servo_handle).
 *
 * Input: byte 0 = flash geometry (bits 0-1), product (bit 2: encoder),
 * controller rules (bits 3-4), weak-cell reads (bits 5-6); byte 1 = the
 * simulator's PRNG seed; then operations, an opcode byte and its arguments:
 *   commit    1-4 (register, u32 value) pairs through the app's commit: any
 *             value, as a store written by another firmware could hold;
 *   maintain  idle compaction calls;
 *   reboot    power cycle, mount, check (below);
 *   cut       arm a power cut at a later flash op with chosen outcomes;
 *   forge     program a record with a valid CRC but chosen contents, at a
 *             chosen page and cell: a snapshot (keys of the schema, unknown
 *             or repeated, any values, version, generation, key hash), a
 *             dense delta (any set of snapshot indices and values), both
 *             with km_rec_encode, or a legacy 'D' delta as older firmware
 *             wrote them;
 *   mutate    rewrite the image as unknown content (every cell "programmed",
 *             as on a part of unknown history) with chosen bytes set or
 *             flipped, or whole pages of random bytes: torn, garbage and
 *             bit-rotted images;
 *   rules     change the controller rules / how weak cells read.
 * A commit or idle call after a forge or mutate reboots first: the store
 * owns its flash while it runs, the edits stand for what a past life (or
 * another firmware, or time) left in it.
 * After the last operation: a reboot, then a few commits on that image and
 * a last reboot.
 *
 * Invariants (abort() on violation):
 *  - mount does no flash program or erase, whatever the image;
 *  - every persisted register in the register file after boot passes the
 *    register's own validation (km_reg_validate: declared range, layout,
 *    cross-field rules) with its canonical value, the angle limits do not
 *    contradict each other (§5.1), and a §2 read of every readable register
 *    answers a well-formed frame whose fixed-size value validates too;
 *  - once a commit succeeded in a session with nothing forged, mutated or
 *    cut since, the next mount loads exactly the acknowledged values. */
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h> /* km_test_support.h needs it; only its products are used */

#include "km_app_userdata.h"
#include "km_frame.h"
#include "km_nor_sim.h"
#include "km_registers.h"
#include "km_servo.h"
#include "km_store.h"
#include "km_store_record.h"
#include "km_crc32.h"

#include "km_test_support.h"

static void prv_check(bool ok)
{
    if (!ok) {
        abort();
    }
}

/* The input as a stream; reads past the end give zeros. */
typedef struct {
    const uint8_t *p;
    size_t n;
    size_t at;
} prv_in_t;

static uint8_t prv_u8(prv_in_t *in)
{
    return in->at < in->n ? in->p[in->at++] : 0u;
}

static uint16_t prv_u16(prv_in_t *in)
{
    const uint16_t lo = prv_u8(in);
    return (uint16_t)(lo | (uint16_t)(prv_u8(in) << 8));
}

static uint32_t prv_u32(prv_in_t *in)
{
    const uint32_t lo = prv_u16(in);
    return lo | ((uint32_t)prv_u16(in) << 16);
}

static const km_nor_sim_config_t s_geoms[4] = {
    {2048u, 8u, 2u, 0xFFu}, /* STM32G0 */
    {1024u, 2u, 2u, 0xFFu}, /* STM32F0 / GD32 */
    {1024u, 4u, 2u, 0xFFu}, /* nRF51 (QEMU ships 0x00 pages: the mutate op) */
    {2048u, 8u, 3u, 0xFFu}, /* STM32G0, three pages */
};

static km_nor_sim_t s_sim;
static km_flash_t s_flash;
static const km_product_t *s_product;
static uint8_t s_addrs[KM_USERDATA_MAX]; /* persisted registers, table order */
static uint8_t s_count;
static uint32_t s_model[KM_USERDATA_MAX]; /* what the next mount must load ... */
static bool s_model_valid;                /* ... when this is true */
/* The image was forged or mutated behind the running store's back: a store
 * does not expect its flash to change under it, so the next commit or idle
 * call comes after a reboot (the image is what a past life left). */
static bool s_offline_edit;

static uint32_t prv_flash_writes(void)
{
    return s_sim.count.programs + s_sim.count.erases;
}

static void prv_schema_addrs(void)
{
    s_count = 0;
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        if (km_reg_table[i].persisted) {
            s_addrs[s_count++] = km_reg_table[i].addr;
        }
    }
}

/* A value passes the checks a bus write of it would, and is canonical. */
static bool prv_value_ok(km_reg_index_t r, const uint8_t *bytes, uint8_t n, uint32_t value)
{
    uint32_t packed = 0;
    return km_reg_validate(r, s_product, bytes, n, &packed) && packed == value;
}

/* Reads every readable register as a master would (§2 read, cmd 0x02). */
static void prv_read_all(km_servo_t *servo)
{
    const uint8_t id = km_servo_id(servo);
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        const km_reg_t *r = &km_reg_table[i];
        if (!(r->access & KM_R)) {
            continue;
        }
        km_frame_t f;
        memset(&f, 0, sizeof f);
        f.id = id;
        f.cmd = 0x02u;
        f.body_len = 1u;
        f.body[0] = r->addr;
        km_reply_t reply;
        memset(&reply, 0, sizeof reply);
        km_servo_handle(servo, &f, &reply);
        /* F9 F5 id len 02 addr value... checksum */
        prv_check(reply.len >= 7u && reply.len <= KM_FRAME_MAX);
        prv_check(reply.bytes[0] == KM_HDR0 && reply.bytes[1] == KM_HDR1_RESPONSE);
        prv_check(reply.bytes[2] == id && reply.bytes[3] == reply.len - 4u);
        prv_check(reply.bytes[4] == 0x02u && reply.bytes[5] == r->addr);
        prv_check(reply.bytes[reply.len - 1u] == km_checksum(&reply.bytes[2], (uint32_t)reply.len - 3u));
        const uint8_t size = km_reg_fixed_size((km_layout_t)r->layout);
        if (r->persisted && size != 0u) {
            prv_check(reply.len - 7u == size);
            prv_check(
                prv_value_ok((km_reg_index_t)i, &reply.bytes[6], size, km_get_le(&reply.bytes[6], size)));
        }
    }
}

/* Power cycle and boot as km_app_init does: mount, then the register file. */
static void prv_reboot(void)
{
    km_nor_sim_power_cycle(&s_sim);
    const uint32_t writes = prv_flash_writes();
    uint32_t values[KM_USERDATA_MAX];
    memset(values, 0xA5, sizeof values);
    const km_store_mount_t m = km_app_userdata_mount(&s_flash, s_product, values);
    prv_check(prv_flash_writes() == writes);
    prv_check(m <= KM_STORE_MOUNT_ERR_ARG && m != KM_STORE_MOUNT_ERR_ARG);
    if (s_model_valid) {
        prv_check(m == KM_STORE_MOUNT_LOADED);
        prv_check(memcmp(values, s_model, (size_t)s_count * sizeof values[0]) == 0);
    }
    memcpy(s_model, values, sizeof s_model);
    s_model_valid = false; /* until a commit settles this session */
    s_offline_edit = false;

    static km_servo_t servo;
    km_servo_init(&servo, s_product, values, 1u, NULL);
    for (unsigned i = 0; i < KM_REG_COUNT; i++) {
        const km_reg_t *r = &km_reg_table[i];
        const uint8_t size = km_reg_fixed_size((km_layout_t)r->layout);
        if (!r->persisted) {
            continue;
        }
        prv_check(size >= 1u && size <= 3u);
        uint8_t bytes[4];
        const uint32_t v = km_servo_reg(&servo, (km_reg_index_t)i);
        km_put_le(bytes, v, size);
        prv_check(prv_value_ok((km_reg_index_t)i, bytes, size, v));
    }
    const int16_t lo = (int16_t)km_servo_reg(&servo, KM_REG_ANGLE_MIN);
    const int16_t hi = (int16_t)km_servo_reg(&servo, KM_REG_ANGLE_MAX);
    prv_check(lo == 0 || hi == 0 || lo < hi);
    prv_read_all(&servo);
}

static void prv_commit(prv_in_t *in)
{
    if (s_offline_edit) {
        prv_reboot();
    }
    const uint8_t n = (uint8_t)(1u + (prv_u8(in) & 3u));
    uint8_t addrs[4];
    uint32_t values[4];
    uint8_t idx[4];
    for (uint8_t i = 0; i < n; i++) {
        idx[i] = (uint8_t)(prv_u8(in) % s_count);
        addrs[i] = s_addrs[idx[i]];
        values[i] = prv_u32(in);
    }
    if (km_app_userdata_commit(addrs, values, n)) {
        bool repeated = false;
        for (uint8_t i = 0; i < n; i++) {
            for (uint8_t j = 0; j < i; j++) {
                repeated = repeated || idx[i] == idx[j];
            }
        }
        prv_check(!repeated); /* the store refuses a key given twice */
        for (uint8_t i = 0; i < n; i++) {
            s_model[idx[i]] = values[i];
        }
        s_model_valid = true;
    } else {
        s_model_valid = false; /* either state may show at the next mount */
    }
}

/* A legacy delta ('D', read only since the dense format): header, entries
 * (key u8, value u32 LE), 0xFF padding, CRC-32, then one zero commit cell,
 * as older firmware wrote them (docs/store.md). */
static uint32_t prv_encode_legacy(uint8_t *buf, const km_store_key_t *keys, const uint32_t *values,
                                  uint8_t count, uint32_t cell)
{
    uint32_t at = KM_REC_HDR_LEGACY;
    for (uint8_t i = 0; i < count; i++) {
        buf[at] = keys[i].key;
        km_put_le(&buf[at + 1u], values[i], 4u);
        at += KM_REC_ENTRY;
    }
    const uint32_t body = (at + KM_REC_CRC + cell - 1u) / cell * cell;
    buf[0] = KM_REC_DELTA_LEGACY;
    buf[1] = count;
    buf[2] = 0u;
    buf[3] = 0u;
    memset(&buf[at], 0xFF, body - KM_REC_CRC - at);
    km_put_le(&buf[body - KM_REC_CRC], km_crc32(0u, buf, body - KM_REC_CRC), 4u);
    memset(&buf[body], 0x00, cell);
    return body + cell;
}

static void prv_forge(prv_in_t *in)
{
    const uint8_t kind = prv_u8(in);
    uint8_t count = (uint8_t)(prv_u8(in) % (KM_STORE_MAX_KEYS + 1u));
    km_store_key_t keys[KM_STORE_MAX_KEYS];
    uint32_t values[KM_STORE_MAX_KEYS];
    uint32_t real_hash = 0;
    for (uint8_t i = 0; i < s_count; i++) {
        real_hash = km_crc32(real_hash, &s_addrs[i], 1u);
    }
    uint8_t type = KM_REC_SNAPSHOT;
    if (kind % 3u == 1u) {
        type = KM_REC_DELTA;
    } else if (kind % 3u == 2u) {
        type = KM_REC_DELTA_LEGACY;
    }
    uint32_t mask = count >= 32u ? 0xFFFFFFFFu : ((1u << count) - 1u);
    if (type == KM_REC_DELTA) {
        /* A dense delta names snapshot indices: any non-empty set of 0..31. */
        count = KM_STORE_MAX_KEYS;
        mask = prv_u32(in);
        mask = mask ? mask : 1u;
    } else if (type == KM_REC_DELTA_LEGACY && count == 0u) {
        count = 1u; /* a delta carries at least one change */
        mask = 1u;
    }
    for (uint8_t i = 0; i < count; i++) {
        keys[i].def = 0;
        keys[i].key = 0;
        values[i] = 0;
        if (type == KM_REC_DELTA && !(mask & (1u << i))) {
            continue;
        }
        const uint8_t k = prv_u8(in);
        /* Mostly the product's keys (repeats allowed), else any byte. */
        keys[i].key = (k & 0x80u) ? (uint8_t)(k & 0x7Fu) : s_addrs[k % s_count];
        values[i] = prv_u32(in);
    }
    const km_store_schema_t fake = {keys, count, 1u};
    km_rec_t rec;
    memset(&rec, 0, sizeof rec);
    rec.type = type;
    rec.version = (kind & 8u) ? prv_u16(in) : 1u; /* 1 = the app's schema version */
    rec.gen = prv_u16(in);                        /* a lifetime of commits, no more */
    rec.hash = (kind & 16u) ? prv_u32(in) : real_hash;
    uint8_t buf[KM_REC_MAX_BYTES];
    const uint32_t size = (type == KM_REC_DELTA_LEGACY)
                              ? prv_encode_legacy(buf, keys, values, count, s_flash.prog_size)
                              : km_rec_encode(buf, &rec, &fake, values, mask, s_flash.prog_size);
    prv_check(size <= sizeof buf);
    const uint32_t page = prv_u8(in) % s_flash.page_count;
    const uint32_t cells = s_flash.page_size / s_flash.prog_size;
    const uint32_t offset = (prv_u16(in) % cells) * s_flash.prog_size;
    if (size <= s_flash.page_size - offset) {
        /* Cell by cell, as the store does: a cell not erased is refused. */
        for (uint32_t at = 0; at < size; at += s_flash.prog_size) {
            (void)s_flash.program(s_flash.ctx, page * s_flash.page_size + offset + at, &buf[at],
                                  s_flash.prog_size);
        }
    }
    s_model_valid = false;
    s_offline_edit = true;
}

static void prv_mutate(prv_in_t *in)
{
    const uint32_t total = s_flash.page_size * s_flash.page_count;
    static uint8_t image[KM_NOR_SIM_MAX_BYTES];
    for (uint32_t at = 0; at < total; at += s_flash.prog_size) {
        if (s_flash.read(s_flash.ctx, at, &image[at], s_flash.prog_size) != KM_FLASH_OK) {
            memset(&image[at], 0x5A, s_flash.prog_size); /* ECC-bad: some garbage */
        }
    }
    const uint8_t n = prv_u8(in);
    for (uint8_t i = 0; i < n && in->at < in->n; i++) {
        const uint8_t how = prv_u8(in);
        const uint32_t at = prv_u16(in) % total;
        const uint8_t v = prv_u8(in);
        if (how & 2u) {
            /* The page holding `at` becomes random bytes (seeded by the input). */
            uint32_t x = 0x9E3779B9u ^ ((uint32_t)how << 16) ^ ((uint32_t)v << 8) ^ at;
            const uint32_t page = at / s_flash.page_size;
            for (uint32_t b = 0; b < s_flash.page_size; b++) {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                image[page * s_flash.page_size + b] = (uint8_t)(x >> 24);
            }
        } else {
            image[at] = (how & 1u) ? (uint8_t)(image[at] ^ v) : v;
        }
    }
    const km_nor_sim_config_t cfg = {s_flash.page_size, s_flash.prog_size, s_flash.page_count, 0x00u};
    const km_nor_sim_rules_t rules = s_sim.rules;
    const km_nor_weak_reads_t weak = s_sim.weak_reads;
    const uint32_t rng = s_sim.rng;
    prv_check(km_nor_sim_init(&s_sim, &cfg, &s_flash));
    km_nor_sim_set_rules(&s_sim, &rules);
    km_nor_sim_set_weak_reads(&s_sim, weak);
    km_nor_sim_seed(&s_sim, rng);
    memcpy(s_sim.data, image, total);
    s_model_valid = false;
    s_offline_edit = true;
}

static void prv_rules(uint8_t b)
{
    const km_nor_sim_rules_t rules = {(b & 1u) != 0u, (b & 2u) != 0u};
    km_nor_sim_set_rules(&s_sim, &rules);
    km_nor_sim_set_weak_reads(&s_sim, (km_nor_weak_reads_t)(((unsigned)b >> 2) % 3u));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2u) {
        return 0;
    }
    prv_in_t in = {data, size, 0};
    const uint8_t cfg = prv_u8(&in);
    prv_check(km_nor_sim_init(&s_sim, &s_geoms[cfg & 3u], &s_flash));
    s_product = (cfg & 4u) ? kt_product_enc() : kt_product_pot();
    prv_rules((uint8_t)(cfg >> 3));
    km_nor_sim_seed(&s_sim, prv_u8(&in));
    prv_schema_addrs();
    s_model_valid = false;
    s_offline_edit = false;
    prv_reboot();

    for (unsigned ops = 0; ops < 64u && in.at < in.n; ops++) {
        const uint8_t op = prv_u8(&in);
        switch (op % 8u) {
        case 0:
        case 1:
            prv_commit(&in);
            break;
        case 2: {
            const uint8_t n = (uint8_t)(prv_u8(&in) & 15u);
            if (s_offline_edit) {
                prv_reboot();
            }
            for (uint8_t i = 0; i < n; i++) {
                (void)km_app_userdata_maintain();
            }
            break;
        }
        case 3:
            prv_reboot();
            break;
        case 4: {
            const uint8_t at = (uint8_t)(prv_u8(&in) & 31u);
            const uint8_t out = prv_u8(&in);
            km_nor_sim_arm_cut(&s_sim, km_nor_sim_ops(&s_sim) + at,
                               (km_nor_prog_outcome_t)(out % KM_NOR_PROG_OUTCOMES),
                               (km_nor_erase_outcome_t)((out >> 4) % KM_NOR_ERASE_OUTCOMES));
            s_model_valid = false;
            break;
        }
        case 5:
            prv_forge(&in);
            break;
        case 6:
            prv_mutate(&in);
            break;
        default:
            prv_rules(prv_u8(&in));
            break;
        }
    }

    /* The image as it ended up: boot on it, then commit on it. */
    prv_reboot();
    for (uint8_t i = 0; i < s_count && i < 3u; i++) {
        const uint8_t addr = s_addrs[(s_count - 1u) - i];
        const uint32_t v = s_model[(s_count - 1u) - i];
        if (km_app_userdata_commit(&addr, &v, 1u)) {
            s_model_valid = true;
        } else {
            s_model_valid = false;
            break;
        }
    }
    prv_reboot();
    return 0;
}
