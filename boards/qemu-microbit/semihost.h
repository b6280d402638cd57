/* SPDX-License-Identifier: Apache-2.0 */
/* ARM semihosting for test images only (never in firmware: without a
 * debugger or QEMU's -semihosting, BKPT 0xAB hard-faults a real part). */
#ifndef KM_SEMIHOST_H
#define KM_SEMIHOST_H

#include <stdint.h>

void km_semihost_write0(const char *s);
void km_semihost_writec(char c);
void km_semihost_write_u32(uint32_t v); /* decimal */
void km_semihost_write_hex(uint32_t v); /* 0x%08x */
_Noreturn void km_semihost_exit(int code);

#endif
