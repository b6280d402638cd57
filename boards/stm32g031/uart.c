/* SPDX-License-Identifier: Apache-2.0 */
/* km_hal_uart on USART1, single-wire half-duplex (HDSEL, RM0444 §33.5.14):
 * TX and RX share PB6, open drain with the bus pull-up. In HDSEL the
 * receiver hears our own transmission; we clear RE for the length of a send
 * and set it again at TC, so the echo never reaches the parser and costs no
 * interrupts. An optional RS-485 DE pin is raised before the first byte and
 * dropped at TC (after the last stop bit).
 *
 * The interrupt handler and km_hal_uart_send (the answer timer's interrupt
 * starts the answer with it) run from RAM, so the bus keeps being served
 * while a flash erase stalls every fetch from flash (docs/flash-busy.md).
 * They take the PRIMASK lock inline for the same reason. */
#include "km_hal_uart.h"

#include "board_clock.h"
#include "board_pins.h"
#include "g0_core.h"
#include "g0_gpio.h"
#include "g0_regs.h"
#include "km_cortex_m.h"
#include "g0_vectors.h"
#include "km_hal_system.h"
#include "km_hal_time.h"
#include "usart_brr.h"

/* The driver's state in one place: the interrupt reaches every field from
 * one base address. A loss (an error flag) is remembered by pointing
 * `call` at prv_rx_after_loss until the next byte: the byte's fast path
 * tests nothing for it. */
static struct {
    km_uart_rx_handler_t call; /* `handler`, or prv_rx_after_loss */
    void *ctx;
    km_uart_rx_handler_t handler;
    const uint8_t *tx_data;
    uint16_t tx_len;
    uint16_t tx_next;
    volatile bool tx_busy;
} s_uart;

/* USART1_ISR's and USART1_RDR's offsets (RM0444 §33.8.9, §33.8.10). */
#define PRV_ISR_OFFSET 0x1Cu
#define PRV_RDR_OFFSET 0x24u

static void prv_de(bool on)
{
#ifdef KM_BOARD_RS485_DE
    if (on) {
        g0_gpio_set(PIN_DE_PORT, PIN_DE_PIN);
    } else {
        g0_gpio_clear(PIN_DE_PORT, PIN_DE_PIN);
    }
#else
    (void)on;
#endif
}

/* The byte after a loss: to the handler with `lost` set, and the next one
 * straight to the handler again. */
G0_RAMFUNC(prv_rx_after_loss) static void prv_rx_after_loss(void *ctx, uint8_t byte, uint32_t tick, bool lost)
{
    (void)lost;
    s_uart.call = s_uart.handler;
    s_uart.handler(ctx, byte, tick, true);
}

/* The handler of a receiver opened with none: the bytes are dropped. */
G0_RAMFUNC(prv_rx_discard) static void prv_rx_discard(void *ctx, uint8_t byte, uint32_t tick, bool lost)
{
    (void)ctx;
    (void)byte;
    (void)tick;
    (void)lost;
}

bool km_hal_uart_init(uint32_t baud, km_uart_rx_handler_t handler, void *ctx)
{
    uint32_t brr = km_usart_brr(BOARD_PCLK_HZ, baud);
    if (brr == 0u) {
        return false;
    }
    g0_nvic_disable(G0_IRQ_USART1);
    s_uart.handler = handler != 0 ? handler : prv_rx_discard;
    s_uart.call = s_uart.handler;
    s_uart.ctx = ctx;
    s_uart.tx_busy = false;

    RCC_APBENR2 |= RCC_APBENR2_USART1;
    g0_gpio_open_drain_pullup(PIN_BUS_PORT, PIN_BUS_PIN);
    g0_gpio_fast(PIN_BUS_PORT, PIN_BUS_PIN);
    g0_gpio_af(PIN_BUS_PORT, PIN_BUS_PIN, PIN_BUS_AF);
#ifdef KM_BOARD_RS485_DE
    g0_gpio_clear(PIN_DE_PORT, PIN_DE_PIN);
    g0_gpio_mode(PIN_DE_PORT, PIN_DE_PIN, G0_GPIO_MODE_OUTPUT);
#endif

    /* Configuration bits are only writable with UE = 0 (§33.8.1). 8N1 and
     * FIFO off are the reset values of CR1/CR2. */
    USART1_CR1 = 0u;
    USART1_CR2 = 0u;
    USART1_CR3 = USART_CR3_HDSEL | USART_CR3_EIE;
    USART1_BRR = brr;
    USART1_ICR = USART_ICR_PECF | USART_ICR_FECF | USART_ICR_NECF | USART_ICR_ORECF | USART_ICR_TCCF;
    USART1_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;

    /* Highest priority: the byte's time stamp is the answer's reference. */
    g0_nvic_enable(G0_IRQ_USART1, 0u);
    return true;
}

G0_RAMFUNC(km_hal_uart_send) bool km_hal_uart_send(const uint8_t *data, uint16_t len)
{
    if (len == 0u) {
        return true;
    }
    uint32_t key = km_cortex_irq_lock();
    if (s_uart.tx_busy) {
        km_cortex_irq_restore(key);
        return false;
    }
    s_uart.tx_busy = true;
    s_uart.tx_data = data;
    s_uart.tx_len = len;
    s_uart.tx_next = 0u;
    prv_de(true);
    USART1_CR1 = (USART1_CR1 & ~(USART_CR1_RE | USART_CR1_RXNEIE)) | USART_CR1_TXEIE;
    km_cortex_irq_restore(key);
    return true;
}

bool km_hal_uart_tx_busy(void)
{
    return s_uart.tx_busy;
}

static void prv_tx(uint32_t isr, uint32_t cr1)
{
    if ((cr1 & USART_CR1_TXEIE) != 0u && (isr & USART_ISR_TXE) != 0u) {
        if (s_uart.tx_next < s_uart.tx_len) {
            USART1_TDR = s_uart.tx_data[s_uart.tx_next++];
        }
        if (s_uart.tx_next >= s_uart.tx_len) {
            /* Last byte queued: TC tells when its stop bit has left the wire. */
            USART1_ICR = USART_ICR_TCCF;
            USART1_CR1 = (USART1_CR1 & ~USART_CR1_TXEIE) | USART_CR1_TCIE;
        }
    } else if ((cr1 & USART_CR1_TCIE) != 0u && (isr & USART_ISR_TC) != 0u) {
        prv_de(false);
        /* RE was off for the whole send, so nothing of our own frame was
         * received; clear any error flag latched around the RE switch. */
        USART1_ICR = USART_ICR_TCCF | USART_ICR_ORECF | USART_ICR_FECF | USART_ICR_NECF | USART_ICR_PECF;
        USART1_CR1 = (USART1_CR1 & ~USART_CR1_TCIE) | USART_CR1_RE | USART_CR1_RXNEIE;
        s_uart.tx_busy = false;
    }
}

/* Receiving (RXNEIE) and sending (TXEIE, then TCIE) never overlap: a send
 * turns RE and RXNEIE off and TC turns them on again. A received byte with
 * no error flag and no loss before it goes to the handler first, before
 * CR1 is read (docs/benchmarks.md "Per byte"): RXNE is only set with RE on,
 * or by a byte that came in just before a send turned RE off, which is then
 * handed over at once instead of at TC. An error flag is cleared and marks
 * the loss whether receiving or not (EIE interrupts even while RX is off).
 * The byte's time stamp is TIM2's count read here (km_hal_time_now's,
 * without the call: this runs for every byte on the bus). */
G0_RAMFUNC(USART1_IRQHandler) void USART1_IRQHandler(void)
{
    uintptr_t usart = USART1_BASE_R;
    __asm__("" : "+l"(usart)); /* ISR and RDR from one base register */
    const uint32_t isr = G0_REG_AT(usart, PRV_ISR_OFFSET);
    const uint32_t errors = USART_ISR_ORE | USART_ISR_FE | USART_ISR_NE | USART_ISR_PE;
    if ((isr & (errors | USART_ISR_RXNE)) != USART_ISR_RXNE) {
        const uint32_t cr1 = USART1_CR1;
        if ((isr & errors) != 0u) {
            USART1_ICR = USART_ICR_ORECF | USART_ICR_FECF | USART_ICR_NECF | USART_ICR_PECF;
            s_uart.call = prv_rx_after_loss;
        }
        if ((cr1 & USART_CR1_RXNEIE) == 0u) {
            prv_tx(isr, cr1);
            return;
        }
        if ((isr & USART_ISR_RXNE) == 0u) {
            return;
        }
    }
    const uint32_t tick = TIM_CNT(TIM2_BASE_R);
    const uint8_t byte = (uint8_t)G0_REG_AT(usart, PRV_RDR_OFFSET); /* reading clears RXNE */
    s_uart.call(s_uart.ctx, byte, tick, false);
}
