/* SPDX-License-Identifier: Apache-2.0 */
/* QEMU timing image: the servo firmware, plus the app's measurement hook
 * printing over semihosting how late each answer started against the delay
 * it asked for. tools/bench/bench-answer-delay runs it under -icount, where
 * virtual time is a function of executed instructions, so the figure is
 * the firmware's own latency (RX stamp, timer interrupt), not host noise. */
#include "km_app.h"
#include "semihost.h"

void km_app_answer_started(uint32_t frame_end, uint32_t started, uint32_t delay_us)
{
    /* The tick is 1 MHz: ticks are microseconds. */
    km_semihost_write0("answer asked_us=");
    km_semihost_write_u32(delay_us);
    km_semihost_write0(" actual_us=");
    km_semihost_write_u32(started - frame_end);
    km_semihost_write0("\n");
}
