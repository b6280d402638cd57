/* SPDX-License-Identifier: Apache-2.0 */
/* The multi-ID commands, sent to the broadcast ID and judged by every
 * servo on the bus: 0x83 write ("Multi-ID write") and 0x82 read ("Multi-ID
 * read 0x82"). Which registers 0x83 may write, with which parameter sizes,
 * is km_registers.def's `multi` column. The list scans are what a long list
 * costs every servo on the bus, listed or not (docs/benchmarks.md "Lists"). */
#include <stddef.h>
#include <string.h>

#include "km_dispatch.h"
#include "km_hooks.h"

/* floor(n / d) for n <= 255, 1 <= d <= 8, as (n x ceil(2^11 / d)) >> 11:
 * exact in that range (tests/unit/protocol/test_dispatch_multi_scan.c);
 * on the M0 a division is a library call. */
static const uint16_t s_recip_2048[9] = {0u, 2048u, 1024u, 683u, 512u, 410u, 342u, 293u, 256u};

/* The first entry of `own` among the entries of `stride` bytes from p (the
 * ID first in each) up to end, or end. Four entries a pass with the stride
 * a constant where the caller inlines it: a load and a compare each. */
static inline __attribute__((always_inline)) const uint8_t *
prv_find_entry(const uint8_t *p, const uint8_t *end, uint8_t own, size_t stride)
{
    while ((size_t)(end - p) >= 4u * stride) {
        if (p[0] == own) {
            return p;
        }
        if (p[stride] == own) {
            return p + stride;
        }
        if (p[2u * stride] == own) {
            return p + 2u * stride;
        }
        if (p[3u * stride] == own) {
            return p + 3u * stride;
        }
        p += 4u * stride;
    }
    while (p < end && *p != own) {
        p += stride;
    }
    return p < end ? p : end;
}

/* prv_find_entry() for the strides 0x83's registers take (KM_K(1), KM_K(2),
 * KM_K(4): 2, 3, 5 bytes an entry), each with its stride a constant. */
static __attribute__((noinline)) const uint8_t *prv_find_multi(const uint8_t *p, const uint8_t *end,
                                                               uint8_t own, size_t stride)
{
    switch (stride) {
    case 2u: /* 0x64's entries, the longest lists (124): eight a pass */
        while ((uint32_t)(end - p) >= 16u && p[0] != own && p[2] != own && p[4] != own && p[6] != own &&
               p[8] != own && p[10] != own && p[12] != own && p[14] != own) {
            p += 16;
        }
        return prv_find_entry(p, end, own, 2u);
    case 3u:
        return prv_find_entry(p, end, own, 3u);
    case 5u:
        return prv_find_entry(p, end, own, 5u);
    default:
        return prv_find_entry(p, end, own, stride);
    }
}

/* "Multi-ID write": F9 FF FE len 83 addr k (id, k bytes)... cs. A listed
 * servo runs its first entry as a write of addr. */
km_report_t km_cmd_multi_write(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    (void)reply;
    /* the parameter sizes the register takes (KM_K() bits), 0 when it may
     * not be multi-written (§3: 0x64 0x65 0x66 0x68 0x6E 0x6F only) */
    const int r = f->body_len >= 1u ? km_reg_find(f->body[0]) : -1;
    const uint8_t sizes = r >= 0 ? km_reg_table[r].multi : 0u;
    if (sizes == 0u) {
        /* §4: an address the command does not support is bit 5, on every
         * servo (each saw the broken command); nothing runs. */
        km_regfile_exception(&s->reg);
        s->sync.full = false;
        return KM_REPORT_NONE;
    }
    const uint32_t n_params = f->body_len >= 2u ? f->body_len - 2u : 0u;
    const uint32_t k = f->body_len >= 2u ? f->body[1] : 0u;
    const uint32_t step = k + 1u;
    /* n_params % step, the division by its reciprocal (k <= 7 here) */
    const uint32_t whole = k <= 7u ? ((n_params * s_recip_2048[step]) >> 11) * step : 0u;
    if (k > 7u || !(sizes & KM_K(k)) || n_params == 0u || whole != n_params) {
        km_regfile_fail(&s->reg); /* the right address with malformed entries: a bad value */
        s->sync.full = false;
        return KM_REPORT_NONE;
    }
    const uint8_t *const end = f->body + f->body_len;
    const uint8_t *const at = prv_find_multi(f->body + 2, end, km_servo_id(s), step);
    if (at == end) {
        return KM_REPORT_NONE; /* not in the list: this servo does nothing at all */
    }
    s->sync.full = false;
    km_reg_write[r](s, (km_reg_index_t)r, at + 1, (uint8_t)k); /* as a write of the register */
    return KM_REPORT_NONE;
}

/* The first pair of words from q up to q_end (pairs) holding a byte equal
 * to the byte of pat (repeated 4 times), or q_end. SWAR: that byte is a
 * zero byte of w = word ^ pat, and (w - 0x01010101) & ~w has a top bit set
 * in some byte exactly when w has a zero byte. A function of its own with
 * nothing else live, so the loop's eight values stay in registers. */
#if defined(__GNUC__) && !defined(__clang__)
#define PRV_LOOP_O2 __attribute__((optimize("O2"))) /* GCC only: clang has no per-function level */
#else
#define PRV_LOOP_O2
#endif
static __attribute__((noinline)) PRV_LOOP_O2 const uint32_t *
prv_find_pair(const uint32_t *q, const uint32_t *q_end, uint32_t pat)
{
    const uint32_t ones = 0x01010101u;
    for (; q != q_end; q += 2) {
        const uint32_t a = q[0] ^ pat;
        const uint32_t b = q[1] ^ pat;
        if ((((a - ones) & ~a) | ((b - ones) & ~b)) & (ones << 7)) {
            break;
        }
    }
    return q;
}

/* The first position of `own` in ids[0..n), or n: bytes up to a word
 * boundary, then two words at a time (prv_find_pair), then the bytes
 * left. */
static __attribute__((noinline)) uint32_t prv_find_id(const uint8_t *ids, uint32_t n, uint8_t own)
{
    const uint8_t *const end = ids + n;
    const uint8_t *p = ids;
    while (p != end && ((uintptr_t)p & 3u) != 0u && *p != own) {
        p++;
    }
    if (p != end && *p != own) {
        /* p is on a word boundary: the pairs of words that fit */
        const uint32_t *const q = __builtin_assume_aligned(p, 4);
        p = (const uint8_t *)prv_find_pair(q, q + (((uint32_t)(end - p) >> 3) << 1), own * 0x01010101u);
    }
    while (p != end && *p != own) {
        p++;
    }
    return (uint32_t)(p - ids);
}

/* "Multi-ID read 0x82": F9 FF FE len 82 addr id_0 .. id_n-1 cs. A listed
 * servo answers exactly what a 0x02 read of addr answers, starting in slot
 * j, j = its first position in the list. */
km_report_t km_cmd_multi_read(km_servo_t *s, const km_frame_view_t *f, km_reply_t *reply)
{
    if (f->body_len < 2u) {
        /* No address, or no ID: a malformed frame, bit 5 on every servo
         * (nobody can answer it); nothing else happens. */
        km_regfile_exception(&s->reg);
        s->sync.full = false;
        return KM_REPORT_NONE;
    }
    const uint8_t addr = f->body[0];
    const uint32_t n = f->body_len - 1u;
    const uint32_t j = prv_find_id(&f->body[1], n, km_servo_id(s));
    const int r = km_dispatch_readable(addr);
    if (j == n) {
        if (r < 0) {
            /* §4: an address the read does not support is bit 5 on every
             * servo, as for 0x83; unlisted servos report it at a ping. */
            km_regfile_exception(&s->reg);
            s->sync.full = false;
        }
        return KM_REPORT_NONE; /* not listed: nothing else changes */
    }
    s->sync.full = false; /* a command to this servo (§3) */
    km_dispatch_read_answer(s, r, addr, j, reply);
    /* As a read: the status register's value is the ping's status byte. */
    return addr == 0x01 && !s->reg.flags ? KM_REPORT_ALL : KM_REPORT_OWN;
}
