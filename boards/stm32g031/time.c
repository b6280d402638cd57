/* SPDX-License-Identifier: Apache-2.0 */
/* km_hal_time on TIM2 (RM0444 §22): 1 MHz free-running 32-bit count, one-shot
 * on compare channel 1; ISR and tick read in RAM (docs/flash-busy.md). */
#include "km_hal_time.h"

#include "board_clock.h"
#include "g0_core.h"
#include "g0_regs.h"
#include "km_cortex_m.h"
#include "g0_vectors.h"
#include "km_hal_system.h"

#define TICK_HZ (KM_HAL_TICK_MHZ * 1000000u)

static km_timer_handler_t s_handler;
static void *s_ctx;

/* KM_HAL_TICK_MHZ (1) MHz. */
uint32_t km_hal_time_tick_hz(void)
{
    return TICK_HZ;
}

/* Starts TIM2 at 1 MHz. */
void km_hal_time_init(void)
{
    RCC_APBENR1 |= RCC_APBENR1_TIM2;
    TIM_CR1(TIM2_BASE_R) = 0u;
    TIM_PSC(TIM2_BASE_R) = BOARD_PCLK_HZ / TICK_HZ - 1u;
    TIM_ARR(TIM2_BASE_R) = 0xFFFFFFFFu;
    TIM_CCMR1(TIM2_BASE_R) = 0u;       /* frozen: flag only */
    TIM_EGR(TIM2_BASE_R) = TIM_EGR_UG; /* load PSC now */
    TIM_SR(TIM2_BASE_R) = 0u;
    TIM_DIER(TIM2_BASE_R) = 0u;
    TIM_CR1(TIM2_BASE_R) = TIM_CR1_CEN;
    g0_nvic_enable(G0_IRQ_TIM2, 1u);
}

/* The µs count. */
G0_RAMFUNC(km_hal_time_now) uint32_t km_hal_time_now(void)
{
    return TIM_CNT(TIM2_BASE_R);
}

/* Arms the one-shot; locked, the UART interrupt may re-arm. */
void km_hal_timer_at(uint32_t at, km_timer_handler_t handler, void *ctx)
{
    uint32_t key = km_hal_irq_lock();
    TIM_DIER(TIM2_BASE_R) &= ~TIM_DIER_CC1IE;
    s_handler = handler;
    s_ctx = ctx;
    TIM_CCR1(TIM2_BASE_R) = at;
    TIM_SR(TIM2_BASE_R) = ~TIM_SR_CC1IF; /* rc_w0 */
    TIM_DIER(TIM2_BASE_R) |= TIM_DIER_CC1IE;
    /* Already past: force the event rather than wait for a wrap. */
    if ((int32_t)(at - km_hal_time_now()) <= 0) {
        TIM_EGR(TIM2_BASE_R) = TIM_EGR_CC1G;
    }
    km_hal_irq_restore(key);
}

/* Disarms the one-shot. */
void km_hal_timer_cancel(void)
{
    uint32_t key = km_hal_irq_lock();
    TIM_DIER(TIM2_BASE_R) &= ~TIM_DIER_CC1IE;
    TIM_SR(TIM2_BASE_R) = ~TIM_SR_CC1IF;
    s_handler = 0;
    km_hal_irq_restore(key);
}

/* Takes and disarms under the lock, calls outside it (so it may re-arm). */
G0_RAMFUNC(TIM2_IRQHandler) void TIM2_IRQHandler(void)
{
    uint32_t key = km_cortex_irq_lock();
    km_timer_handler_t handler = 0;
    void *ctx = s_ctx;
    if ((TIM_SR(TIM2_BASE_R) & TIM_SR_CC1IF) != 0u) {
        TIM_SR(TIM2_BASE_R) = ~TIM_SR_CC1IF;
        if ((TIM_DIER(TIM2_BASE_R) & TIM_DIER_CC1IE) != 0u) {
            TIM_DIER(TIM2_BASE_R) &= ~TIM_DIER_CC1IE;
            handler = s_handler;
            s_handler = 0;
        }
    }
    km_cortex_irq_restore(key);
    if (handler != 0) {
        handler(ctx);
    }
}
