/* SPDX-License-Identifier: Apache-2.0 */
/* The multi-ID commands, sent to the broadcast ID and judged by every
 * servo on the bus: 0x83 write ("Multi-ID write") and 0x82 read ("Multi-ID
 * read 0x82"). Which registers 0x83 may write, with which parameter sizes,
 * is km_registers.def's `multi` column. */
#include "km_dispatch.h"
#include "km_hooks.h"

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
    const uint8_t n_params = f->body_len >= 2u ? (uint8_t)(f->body_len - 2u) : 0u;
    const uint8_t k = f->body_len >= 2u ? f->body[1] : 0u;
    if (k > 7u || !(sizes & KM_K(k)) || n_params == 0u || n_params % (k + 1u) != 0u) {
        km_regfile_fail(&s->reg); /* the right address with malformed entries: a bad value */
        s->sync.full = false;
        return KM_REPORT_NONE;
    }
    /* The scan over up to 49 entries: the ID, the body and its end in
     * locals (the loop's stores could alias them otherwise). */
    const uint8_t own = km_servo_id(s);
    const uint8_t *const body = f->body;
    const uint8_t len = f->body_len;
    const uint8_t step = (uint8_t)(k + 1u);
    for (uint8_t off = 2; off < len; off = (uint8_t)(off + step)) {
        if (body[off] == own) {
            s->sync.full = false;
            km_reg_write[r](s, (km_reg_index_t)r, &body[off + 1u], k); /* as a write of the register */
            return KM_REPORT_NONE;
        }
    }
    return KM_REPORT_NONE; /* not in the list: this servo does nothing at all */
}

/* The first position of `own` in ids[0..n), or n. Four IDs a pass, then
 * the rest: the scan is what a long list costs (tools/bench/bench-m0); the
 * answer is due j slots later anyway. A function of its own, so the loop
 * has the registers to itself. */
static __attribute__((noinline)) uint32_t prv_find_id(const uint8_t *ids, uint32_t n, uint8_t own)
{
    const uint8_t *const end = ids + n;
    const uint8_t *const end4 = ids + (n & ~3u); /* the whole groups of four */
    const uint8_t *p = ids;
    while (p != end4 && p[0] != own && p[1] != own && p[2] != own && p[3] != own) {
        p += 4;
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
