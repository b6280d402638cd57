/* SPDX-License-Identifier: Apache-2.0 */
/* The few C run-time routines the STM32G031 bootloader links, written for
 * size (docs/update.md §1: the bootloader fits pages 0-1, 4 KiB): newlib's
 * memcpy/memset/memcmp/memmove (552 B, unrolled for speed) and libgcc's
 * division (266 B unsigned, 460 B signed, unrolled) become byte and bit
 * loops of a few dozen bytes. The bootloader copies and compares at most a
 * page-sized buffer and divides a handful of times per frame, so the loops
 * cost no measurable time; the 32 KiB build's application links them too
 * (KM_G031_COMPACT_RT, docs/footprint.md). Linked before libc and libgcc,
 * so these definitions win. Built with -fno-tree-loop-distribute-patterns:
 * GCC must not turn the loops below back into calls to themselves.
 * Division by zero is defined: quotient 0xFFFFFFFF (unsigned; signed: -1
 * for a dividend >= 0, 1 below 0), remainder the dividend. */
#include <stddef.h>
#include <stdint.h>

void *memcpy(void *dst, const void *src, size_t n);
void *memset(void *dst, int c, size_t n);
void *memmove(void *dst, const void *src, size_t n);
int memcmp(const void *a, const void *b, size_t n);
uint32_t __aeabi_uidiv(uint32_t n, uint32_t d);
uint64_t __aeabi_uidivmod(uint32_t n, uint32_t d);
int32_t __aeabi_idiv(int32_t n, int32_t d);
uint64_t __aeabi_idivmod(int32_t n, int32_t d);

/* memmove's loops serve memcpy too: one copy routine (written without
 * restrict, so GCC cannot turn the memmove back into a memcpy). */
void *memcpy(void *dst, const void *src, size_t n)
{
    return memmove(dst, src, n);
}

void *memmove(void *dst, const void *src, size_t n)
{
    uint8_t *d = dst;
    const uint8_t *s = src;
    if (d < s) {
        while (n-- > 0u) {
            *d++ = *s++;
        }
    } else {
        while (n-- > 0u) {
            d[n] = s[n];
        }
    }
    return dst;
}

void *memset(void *dst, int c, size_t n)
{
    uint8_t *d = dst;
    while (n-- > 0u) {
        *d++ = (uint8_t)c;
    }
    return dst;
}

int memcmp(const void *a, const void *b, size_t n)
{
    const uint8_t *x = a;
    const uint8_t *y = b;
    for (; n > 0u; n--, x++, y++) {
        if (*x != *y) {
            return (int)*x - (int)*y;
        }
    }
    return 0;
}

/* Quotient in the low word, remainder in the high word: the AEABI returns
 * a 64-bit value in r0:r1, which is the uidivmod contract (r0 quotient,
 * r1 remainder). Restoring shift-and-subtract, one bit per step. A
 * division by zero gives quotient 0xFFFFFFFF, remainder n (libgcc would
 * call __aeabi_idiv0; no divisor here is ever zero: they are page sizes,
 * cell sizes, 128 and a baud checked to be 9600..1000000). */
uint64_t __aeabi_uidivmod(uint32_t n, uint32_t d)
{
    uint32_t q = 0u;
    uint32_t r = 0u;
    for (uint32_t bit = 32u; bit-- > 0u;) {
        r = (r << 1) | ((n >> bit) & 1u);
        q <<= 1;
        if (r >= d) {
            r -= d;
            q |= 1u;
        }
    }
    return ((uint64_t)r << 32) | q;
}

uint32_t __aeabi_uidiv(uint32_t n, uint32_t d)
{
    return (uint32_t)__aeabi_uidivmod(n, d);
}

/* Signed: the unsigned division of the magnitudes, the quotient negated
 * when the signs differ and the remainder given the dividend's sign (C's
 * truncation); quotient low word, remainder high word as above. */
uint64_t __aeabi_idivmod(int32_t n, int32_t d)
{
    const uint32_t un = n < 0 ? 0u - (uint32_t)n : (uint32_t)n;
    const uint32_t ud = d < 0 ? 0u - (uint32_t)d : (uint32_t)d;
    const uint64_t qr = __aeabi_uidivmod(un, ud);
    uint32_t q = (uint32_t)qr;
    uint32_t r = (uint32_t)(qr >> 32);
    if ((n < 0) != (d < 0)) {
        q = 0u - q;
    }
    if (n < 0) {
        r = 0u - r;
    }
    return ((uint64_t)r << 32) | q;
}

int32_t __aeabi_idiv(int32_t n, int32_t d)
{
    return (int32_t)(uint32_t)__aeabi_idivmod(n, d);
}
