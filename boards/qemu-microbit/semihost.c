/* SPDX-License-Identifier: Apache-2.0 */
/* Semihosting calls: SYS_WRITEC/SYS_WRITE0 for logs, SYS_EXIT_EXTENDED for
 * an exit code QEMU passes on as its own (test images only). */
#include "semihost.h"

#define PRV_SYS_WRITEC 0x03u
#define PRV_SYS_WRITE0 0x04u
#define PRV_SYS_EXIT 0x18u
#define PRV_SYS_EXIT_EXTENDED 0x20u
#define PRV_ADP_STOPPED_APPLICATION_EXIT 0x20026u

static uint32_t prv_call(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void km_semihost_write0(const char *s)
{
    (void)prv_call(PRV_SYS_WRITE0, s);
}

void km_semihost_writec(char c)
{
    (void)prv_call(PRV_SYS_WRITEC, &c);
}

void km_semihost_write_u32(uint32_t v)
{
    char buf[11];
    uint32_t i = sizeof buf - 1u;
    buf[i] = '\0';
    do {
        buf[--i] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v != 0u);
    km_semihost_write0(&buf[i]);
}

void km_semihost_write_hex(uint32_t v)
{
    static const char s_digits[] = "0123456789abcdef";
    char buf[11] = "0x";
    for (uint32_t i = 0; i < 8u; i++) {
        buf[2u + i] = s_digits[(v >> (28u - 4u * i)) & 0xFu];
    }
    buf[10] = '\0';
    km_semihost_write0(buf);
}

_Noreturn void km_semihost_exit(int code)
{
    const uint32_t block[2] = {PRV_ADP_STOPPED_APPLICATION_EXIT, (uint32_t)code};
    (void)prv_call(PRV_SYS_EXIT_EXTENDED, block);
    /* Hosts without the extended call: plain exit (code lost: 0 or 1). */
    (void)prv_call(PRV_SYS_EXIT,
                   (const void *)(uintptr_t)(code == 0 ? PRV_ADP_STOPPED_APPLICATION_EXIT : 0x20023u));
    for (;;) {
    }
}
