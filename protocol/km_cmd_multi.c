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

/* The strided loops at -O2 (rotated: one compare a pass) in the -Os build. */
#if defined(__GNUC__) && !defined(__clang__)
#define PRV_LOOP_O2 __attribute__((optimize("O2"))) /* GCC only: clang has no per-function level */
#else
#define PRV_LOOP_O2
#endif

/* A word of a frame's bytes: read as words, they may alias the bytes. */
typedef uint32_t __attribute__((may_alias)) prv_word_t;

/* The one-by-one scan's inlining: a call in the 32 KiB build (KM_PROTOCOL_COMPACT, docs/footprint.md). */
#if defined(KM_PROTOCOL_COMPACT) && KM_PROTOCOL_COMPACT
#define PRV_EACH_INLINE __attribute__((noinline))
#else
#define PRV_EACH_INLINE inline __attribute__((always_inline))
#endif

/* floor(n / d) for n <= 255, 1 <= d <= 8, as (n x ceil(2^11 / d)) >> 11:
 * exact in that range (tests/unit/protocol/test_dispatch_multi_scan.c);
 * on the M0 a division is a library call. */
static const uint16_t s_recip_2048[9] = {0u, 2048u, 1024u, 683u, 512u, 410u, 342u, 293u, 256u};

/* The first entry of `own` among the entries of `stride` bytes from p up
 * to end (the ID first in each), or end: one by one. */
static PRV_EACH_INLINE const uint8_t *prv_find_each(const uint8_t *p, const uint8_t *const end,
                                                    const uint8_t own, const size_t stride)
{
    while (p < end && *p != own) {
        p += stride;
    }
    return p < end ? p : end;
}

/* The first word from q up to q_end (q < q_end, whole blocks of four) in which a byte that k
 * marks (bit 0 of each entry's ID byte) equals the byte of pat (own, four
 * times), or q_end. SWAR: with x = word ^ pat, (x - k) & ~x has a bit 7
 * set only in a marked byte that is zero, or above one through a chain
 * of borrows, so exactly when some marked byte matches: the value bytes in
 * between never count (docs/benchmarks.md "Lists"). A function of its own
 * so the loop's values stay in registers. */
static __attribute__((noinline)) const prv_word_t *
prv_find_block(const prv_word_t *q, const prv_word_t *const q_end, const uint32_t pat, const uint32_t k)
{
    do {
        uint32_t x = *q++ ^ pat;
        uint32_t marked = (x - k) & ~x;
        x = *q++ ^ pat;
        marked |= (x - k) & ~x;
        x = *q++ ^ pat;
        marked |= (x - k) & ~x;
        x = *q++ ^ pat;
        marked |= (x - k) & ~x;
        if (marked & 0x80808080u) {
            q -= 4;
            while (!(((*q ^ pat) - k) & ~(*q ^ pat) & 0x80808080u)) {
                q++; /* the word of the four that holds it */
            }
            return q;
        }
    } while (q != q_end);
    return q;
}

/* The first entry of `own` among the entries of `stride` (1 or 2) bytes
 * from p up to end (the ID first in each), or end: the entries before a
 * word boundary one by one, then blocks of 16 bytes (prv_find_block), then
 * one by one from the word that holds it or from the rest. */
static __attribute__((noinline)) const uint8_t *prv_find_words(const uint8_t *p, const uint8_t *const end,
                                                               const uint8_t own, const uint32_t stride)
{
    const uint8_t *const aligned = (const uint8_t *)(((uintptr_t)p + 3u) & ~(uintptr_t)3u);
    while (p < aligned && p < end && *p != own) {
        p += stride;
    }
    if (p >= aligned && p < end && *p != own) {
        /* p - aligned: 0, or 1 (stride 2 from an odd address); the same in every block */
        const uint32_t phase = (uint32_t)(p - aligned);
        const uint32_t k = (stride == 1u ? 0x01010101u : 0x00010001u) << (8u * phase);
        const prv_word_t *const q = __builtin_assume_aligned(aligned, 4);
        const prv_word_t *const q_end = q + (((uint32_t)(end - aligned) >> 4) << 2);
        if (q != q_end) {
            p = (const uint8_t *)prv_find_block(q, q_end, own * 0x01010101u, k) + phase;
        }
    }
    return prv_find_each(p, end, own, stride);
}

/* Whether one of the six entries of `stride` bytes from p is `own`'s. */
static inline __attribute__((always_inline)) bool prv_in_six(const uint8_t *p, const uint8_t own,
                                                             const size_t stride)
{
    return p[0] == own || p[stride] == own || p[2u * stride] == own || p[3u * stride] == own ||
           p[4u * stride] == own || p[5u * stride] == own;
}

/* The first entry of `own` among the entries of `stride` bytes from p up
 * to end (the ID first in each), or end: `per_pass` entries a pass (the
 * stride a constant where inlined: a load and a compare each), then one
 * by one from the pass that holds it or from the rest. */
static inline __attribute__((always_inline)) const uint8_t *
prv_find_bytes(const uint8_t *p, const uint8_t *const end, const uint8_t own, const size_t stride)
{
    const size_t pass = (stride <= 3u ? 8u : 6u) * stride; /* offsets within ldrb's 0..31 */
    if ((size_t)(end - p) >= pass) {
        const uint8_t *const last = end - pass;
        do {
            if (prv_in_six(p, own, stride) ||
                (stride <= 3u && (p[6u * stride] == own || p[7u * stride] == own))) {
                break;
            }
            p += pass;
        } while (p <= last);
    }
    return prv_find_each(p, end, own, stride);
}

/* The first entry of `own` among 0x83's entries from p up to end, or end,
 * for the strides its registers take (KM_K(1), KM_K(2), KM_K(4): 2, 3, 5
 * bytes an entry): two a word for 2, one by one with the stride a
 * constant for 3 and 5. */
static __attribute__((noinline)) PRV_LOOP_O2 const uint8_t *
prv_find_multi(const uint8_t *p, const uint8_t *const end, const uint8_t own, const uint32_t stride)
{
    switch (stride) {
    case 2u:
        return prv_find_words(p, end, own, 2u);
    case 3u:
        return prv_find_bytes(p, end, own, 3u);
    case 5u:
        return prv_find_bytes(p, end, own, 5u);
    default: /* no register takes another size today */
        return prv_find_each(p, end, own, stride);
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
    km_reg_write(r)(s, (km_reg_index_t)r, at + 1, (uint8_t)k); /* as a write of the register */
    return KM_REPORT_NONE;
}

#if KM_FEATURE_MULTI_READ
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
    const uint8_t *const ids = &f->body[1];
    const uint32_t j = (uint32_t)(prv_find_words(ids, ids + n, km_servo_id(s), 1u) - ids);
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
#endif
