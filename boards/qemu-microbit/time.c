/* SPDX-License-Identifier: Apache-2.0 */
/* Time (km_hal_time.h) on nRF51 TIMER0: 32-bit, 1 MHz, free running; CC[0]
 * reads the count, CC[1] is the one-shot (docs/architecture.md "qemu-microbit's time"). */
#include <stdbool.h>
#include <stddef.h>

#include "km_hal_system.h"
#include "km_hal_time.h"
#include "nrf51_regs.h"

#define PRV_TICK_HZ (KM_HAL_TICK_MHZ * 1000000u)
#define PRV_PRESCALER 4u /* 16 MHz >> 4 = 1 MHz */
_Static_assert(KM_HAL_TICK_MHZ == 1u, "TIMER0's prescaler gives 1 MHz");
#define PRV_CC_NOW 0u
#define PRV_CC_SHOT 1u

static km_timer_handler_t s_shot_handler;
static void *s_shot_ctx;
static volatile bool s_shot_forced; /* fired by software: `at` had already passed */

uint32_t km_hal_time_tick_hz(void)
{
    return PRV_TICK_HZ;
}

void km_hal_time_init(void)
{
    NRF_REG(NRF_TIMER0, TIMER_TASKS_STOP) = 1u;
    NRF_REG(NRF_TIMER0, TIMER_MODE) = 0u; /* timer, not counter */
    NRF_REG(NRF_TIMER0, TIMER_BITMODE) = TIMER_BITMODE_32;
    NRF_REG(NRF_TIMER0, TIMER_PRESCALER) = PRV_PRESCALER;
    NRF_REG(NRF_TIMER0, TIMER_SHORTS) = 0u;
    NRF_REG(NRF_TIMER0, TIMER_INTENCLR) = 0xFFFFFFFFu;
    NRF_REG(NRF_TIMER0, TIMER_EVENTS_COMPARE(PRV_CC_SHOT)) = 0u;
    NRF_REG(NRF_TIMER0, TIMER_TASKS_CLEAR) = 1u;
    NRF_REG(NRF_TIMER0, TIMER_TASKS_START) = 1u;
    nrf_irq_enable(NRF_IRQ_TIMER0);
}

/* Capture and read are not atomic: if an interrupt captures in between, the
 * caller reads that later value, which still lies within its own call. */
uint32_t km_hal_time_now(void)
{
    NRF_REG(NRF_TIMER0, TIMER_TASKS_CAPTURE(PRV_CC_NOW)) = 1u;
    return NRF_REG(NRF_TIMER0, TIMER_CC(PRV_CC_NOW));
}

void km_hal_timer_at(uint32_t at, km_timer_handler_t handler, void *ctx)
{
    uint32_t irq = km_hal_irq_lock();
    NRF_REG(NRF_TIMER0, TIMER_INTENCLR) = TIMER_INT_COMPARE(PRV_CC_SHOT);
    NRF_REG(NRF_TIMER0, TIMER_EVENTS_COMPARE(PRV_CC_SHOT)) = 0u;
    s_shot_handler = handler;
    s_shot_ctx = ctx;
    s_shot_forced = false;
    NRF_REG(NRF_TIMER0, TIMER_CC(PRV_CC_SHOT)) = at;
    NRF_REG(NRF_TIMER0, TIMER_INTENSET) = TIMER_INT_COMPARE(PRV_CC_SHOT);
    /* A target already reached is pended by hand; the ISR fires once. */
    if ((int32_t)(at - km_hal_time_now()) <= 0) {
        s_shot_forced = true;
        nrf_irq_pend(NRF_IRQ_TIMER0);
    }
    km_hal_irq_restore(irq);
}

void km_hal_timer_cancel(void)
{
    uint32_t irq = km_hal_irq_lock();
    NRF_REG(NRF_TIMER0, TIMER_INTENCLR) = TIMER_INT_COMPARE(PRV_CC_SHOT);
    NRF_REG(NRF_TIMER0, TIMER_EVENTS_COMPARE(PRV_CC_SHOT)) = 0u;
    s_shot_handler = NULL;
    s_shot_forced = false;
    km_hal_irq_restore(irq);
}

void TIMER0_IRQHandler(void)
{
    bool hw = NRF_REG(NRF_TIMER0, TIMER_EVENTS_COMPARE(PRV_CC_SHOT)) != 0u;
    if (!hw && !s_shot_forced) {
        return;
    }
    NRF_REG(NRF_TIMER0, TIMER_INTENCLR) = TIMER_INT_COMPARE(PRV_CC_SHOT);
    NRF_REG(NRF_TIMER0, TIMER_EVENTS_COMPARE(PRV_CC_SHOT)) = 0u;
    (void)NRF_REG(NRF_TIMER0, TIMER_EVENTS_COMPARE(PRV_CC_SHOT)); /* see uart.c */
    s_shot_forced = false;
    /* Disarm before calling: the handler may re-arm. */
    km_timer_handler_t handler = s_shot_handler;
    void *ctx = s_shot_ctx;
    s_shot_handler = NULL;
    if (handler != NULL) {
        handler(ctx);
    }
}
