/* SPDX-License-Identifier: Apache-2.0 */
/* UART0 as the servo bus (km_hal_uart.h) on the nRF51: RX and TX one interrupt
 * per byte, RX stamped in the ISR (docs/architecture.md "qemu-microbit's UART"). */
#include <stddef.h>

#include "km_board.h"
#include "km_hal_system.h"
#include "km_hal_time.h"
#include "km_hal_uart.h"
#include "nrf51_regs.h"

/* micro:bit edge-connector pins; QEMU ignores PSEL, a real part needs them. */
#define PRV_PIN_TXD 24u
#define PRV_PIN_RXD 25u

#define PRV_BAUD_MIN 1200u
#define PRV_BAUD_MAX 1000000u

/* Run-time option words at 0x20000000, written by QEMU's -device loader
 * (boards/qemu-microbit/README.md "Run-time options"); volatile. */
#define PRV_CONFIG_MAGIC 0x4B4D4746u /* "KMGF" */
/* and -device loader,addr=0x2000000C,data=<slot floor us>,data-len=4 */
#define PRV_GAP_FLOOR_DEFAULT_US 20000u

typedef struct {
    uint32_t magic;
    uint32_t gap_floor_us;
    uint32_t product; /* km_board_option_product() */
    uint32_t slot_floor_us;
} prv_config_t;

__attribute__((section(".km_config"), used)) static volatile prv_config_t s_config;

static km_uart_rx_handler_t s_rx_handler;
static void *s_rx_ctx;
static const uint8_t *volatile s_tx_data;
static volatile uint16_t s_tx_left;
static volatile bool s_tx_busy;
static bool s_rx_lost; /* an error seen with no byte yet to attach it to */

/* BAUDRATE = baud * 2^32 / 16 MHz with the low 12 bits dropped: this yields
 * exactly the RM's table (115200 -> 0x01D7E000, 1M -> 0x10000000). The real
 * rate is then (reg >> 12) * 16 MHz / 2^20. */
static bool prv_baud_reg(uint32_t baud, uint32_t *reg)
{
    if (baud < PRV_BAUD_MIN || baud > PRV_BAUD_MAX) {
        return false;
    }
    uint32_t r = (uint32_t)(((uint64_t)baud << 32) / NRF_HFCLK_HZ) & ~0xFFFu;
    uint32_t actual = (uint32_t)(((uint64_t)(r >> 12) * NRF_HFCLK_HZ) >> 20);
    uint32_t err = actual > baud ? actual - baud : baud - actual;
    if (err * 50u > baud) { /* more than 2 % off */
        return false;
    }
    *reg = r;
    return true;
}

bool km_hal_uart_init(uint32_t baud, km_uart_rx_handler_t handler, void *ctx)
{
    uint32_t reg;
    if (!prv_baud_reg(baud, &reg)) {
        return false;
    }
    s_rx_handler = handler;
    s_rx_ctx = ctx;
    s_tx_busy = false;
    s_tx_left = 0u;

    /* RM §29.2: TXD idles high as a GPIO output, RXD is an input. */
    NRF_REG(NRF_GPIO, GPIO_OUTSET) = 1u << PRV_PIN_TXD;
    NRF_REG(NRF_GPIO, GPIO_PIN_CNF(PRV_PIN_TXD)) = GPIO_PIN_CNF_OUTPUT;
    NRF_REG(NRF_GPIO, GPIO_PIN_CNF(PRV_PIN_RXD)) = GPIO_PIN_CNF_INPUT;
    NRF_REG(NRF_UART0, UART_PSELTXD) = PRV_PIN_TXD;
    NRF_REG(NRF_UART0, UART_PSELRXD) = PRV_PIN_RXD;
    NRF_REG(NRF_UART0, UART_PSELRTS) = UART_PSEL_DISCONNECTED;
    NRF_REG(NRF_UART0, UART_PSELCTS) = UART_PSEL_DISCONNECTED;
    NRF_REG(NRF_UART0, UART_CONFIG) = 0u; /* no parity, no flow control */
    NRF_REG(NRF_UART0, UART_BAUDRATE) = reg;
    /* QEMU drops every register write until ENABLE = 4, so it goes first. */
    NRF_REG(NRF_UART0, UART_ENABLE) = UART_ENABLE_ENABLED;
    NRF_REG(NRF_UART0, UART_EVENTS_RXDRDY) = 0u;
    NRF_REG(NRF_UART0, UART_EVENTS_TXDRDY) = 0u;
    NRF_REG(NRF_UART0, UART_EVENTS_ERROR) = 0u;
    NRF_REG(NRF_UART0, UART_INTENSET) = UART_INT_RXDRDY | UART_INT_TXDRDY;
    NRF_REG(NRF_UART0, UART_TASKS_STARTRX) = 1u;
    nrf_irq_enable(NRF_IRQ_UART0);
    return true;
}

bool km_hal_uart_send(const uint8_t *data, uint16_t len)
{
    if (len == 0u) {
        return true;
    }
    /* Called from main and from the response-delay timer ISR alike. */
    uint32_t irq = km_hal_irq_lock();
    if (s_tx_busy) {
        km_hal_irq_restore(irq);
        return false;
    }
    s_tx_busy = true;
    s_tx_data = data + 1;
    s_tx_left = (uint16_t)(len - 1u);
    NRF_REG(NRF_UART0, UART_EVENTS_TXDRDY) = 0u;
    NRF_REG(NRF_UART0, UART_TASKS_STARTTX) = 1u;
    NRF_REG(NRF_UART0, UART_TXD) = data[0];
    km_hal_irq_restore(irq);
    return true;
}

bool km_hal_uart_tx_busy(void)
{
    return s_tx_busy;
}

/* QEMU hands UART bytes to the guest when the host schedules the emulator,
 * which can pause for milliseconds between two bytes of one frame; 20 ms
 * by default, so a frame is not cut by a host stall. 0 (set by the loader
 * word) gives the parser's real rule. */
uint32_t km_board_option_gap_floor_us(void)
{
    if (s_config.magic != PRV_CONFIG_MAGIC) {
        return PRV_GAP_FLOOR_DEFAULT_US;
    }
    return s_config.gap_floor_us;
}

/* QEMU runs each servo of a bus in its own process, when the host schedules
 * it: on a loaded host an answer can start a millisecond late, more than a
 * super-ID slot at 115200 baud. 0 by default (the slot rule alone); the
 * loader word sets a floor (docs/protocol-decisions.md "Answer slots on
 * emulated buses"). */
uint32_t km_board_option_slot_floor_us(void)
{
    if (s_config.magic != PRV_CONFIG_MAGIC) {
        return 0u;
    }
    return s_config.slot_floor_us;
}

/* Not a bus option, but it lives in the same words (one RAM block the
 * linker script places at 0x20000000); the board's main reads it. */
uint32_t km_board_option_product(void)
{
    if (s_config.magic != PRV_CONFIG_MAGIC) {
        return 0u;
    }
    return s_config.product;
}

/* TXDRDY means the byte has left the shift register, so after the last one
 * the line is idle and the transmitter can stop (saves current on a part). */
static void ISR_prv_tx_done_byte(void)
{
    NRF_REG(NRF_UART0, UART_EVENTS_TXDRDY) = 0u;
    if (s_tx_left > 0u) {
        const uint8_t *p = s_tx_data;
        s_tx_data = p + 1;
        s_tx_left = (uint16_t)(s_tx_left - 1u);
        NRF_REG(NRF_UART0, UART_TXD) = *p;
    } else {
        NRF_REG(NRF_UART0, UART_TASKS_STOPTX) = 1u;
        s_tx_busy = false;
    }
}

void UART0_IRQHandler(void)
{
    if (NRF_REG(NRF_UART0, UART_EVENTS_ERROR) != 0u) {
        /* Overrun/framing/break: the next byte follows a gap in the data. */
        NRF_REG(NRF_UART0, UART_EVENTS_ERROR) = 0u;
        NRF_REG(NRF_UART0, UART_ERRORSRC) = NRF_REG(NRF_UART0, UART_ERRORSRC);
        s_rx_lost = true;
    }
    /* Drain every byte now ready: QEMU queues up to 6 and re-raises RXDRDY
     * after each RXD read; the event must be cleared before reading RXD. */
    while (NRF_REG(NRF_UART0, UART_EVENTS_RXDRDY) != 0u) {
        NRF_REG(NRF_UART0, UART_EVENTS_RXDRDY) = 0u;
        uint8_t byte = (uint8_t)NRF_REG(NRF_UART0, UART_RXD);
        uint32_t tick = km_hal_time_now();
        if (s_rx_handler != NULL) {
            s_rx_handler(s_rx_ctx, byte, tick, s_rx_lost);
        }
        s_rx_lost = false;
    }
    if (NRF_REG(NRF_UART0, UART_EVENTS_TXDRDY) != 0u) {
        if (s_tx_busy) {
            ISR_prv_tx_done_byte();
        } else {
            NRF_REG(NRF_UART0, UART_EVENTS_TXDRDY) = 0u; /* stale: would re-fire forever */
        }
    }
    /* Read back so the event clears reach the peripheral before return,
     * else the interrupt may re-enter once for nothing (RM §9.1.5). */
    (void)NRF_REG(NRF_UART0, UART_EVENTS_RXDRDY);
}
