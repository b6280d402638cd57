/* SPDX-License-Identifier: Apache-2.0 */
/* The bootloader's board part for the STM32G031 (km_boot_board.h), kept
 * small for the 4 KiB budget: the reset clock (HSI16, 16 MHz: no PLL to
 * set up), TIM2 at 1 MHz, USART1 single-wire half-duplex on PB6 polled,
 * the flash controller over the application region (erase, double-word
 * program, reads that report a double ECC error), a read-only view of the
 * store, the IWDG, and the jump (VTOR set to the image's table where the
 * header is 256 B; docs/update.md §2, §5); the 64 KiB build sleeps
 * between bytes (km_bootb_wait). Runs from flash with no interrupt
 * enabled, so a page erase simply stalls it (docs/flash-busy.md concerns
 * the application's bus interrupts, which are off here). */
#include <stdint.h>
#include <string.h>

#include "board_pins.h"
#include "boot_layout.h"
#include "g0_core.h"
#include "g0_regs.h"
#include "km_boot_board.h"

#define PRV_HSI_HZ 16000000u
#define PRV_CELL 8u
#define PRV_PAGE 2048u
#define PRV_SCB_VTOR G0_REG(0xE000ED08u)

_Static_assert(PIN_BUS_PORT == GPIOB_BASE_R && PIN_BUS_AF == 0u,
               "km_bootb_uart_init: the bus pin is on port B, AF0");

extern volatile uint32_t km_boot_ecc_errors;

volatile km_boot_shared_t *km_bootb_shared(void)
{
    return (volatile km_boot_shared_t *)(uintptr_t)BOOT_SHARED_ADDR;
}

void km_bootb_init(void)
{
    RCC_APBENR1 = RCC_APBENR1_TIM2; /* from reset: nothing else on APB1 is on */
    TIM_PSC(TIM2_BASE_R) = PRV_HSI_HZ / 1000000u - 1u;
    TIM_ARR(TIM2_BASE_R) = 0xFFFFFFFFu;
    TIM_EGR(TIM2_BASE_R) = TIM_EGR_UG;
    TIM_CR1(TIM2_BASE_R) = TIM_CR1_CEN;
}

uint32_t km_bootb_now_us(void)
{
    return TIM_CNT(TIM2_BASE_R);
}

uint32_t km_bootb_hw_version(void)
{
    return 0x10u;
}

void km_bootb_factory(void)
{
    /* A real part is programmed in the factory: nothing to install. */
}

/* ---- flash ---------------------------------------------------------------- */

static bool prv_done(void)
{
    while ((FLASH_SR & (FLASH_SR_BSY1 | FLASH_SR_CFGBSY)) != 0u) {
    }
    const bool ok = (FLASH_SR & FLASH_SR_ERRORS) == 0u;
    FLASH_SR = FLASH_SR_ERRORS | FLASH_SR_EOP;
    FLASH_CR = FLASH_CR_LOCK;
    return ok;
}

static void prv_unlock(void)
{
    if ((FLASH_CR & FLASH_CR_LOCK) != 0u) {
        FLASH_KEYR = FLASH_KEY1;
        FLASH_KEYR = FLASH_KEY2;
    }
    FLASH_SR = FLASH_SR_ERRORS | FLASH_SR_EOP;
}

static km_flash_result_t prv_erase(void *ctx, uint32_t page)
{
    (void)ctx;
    if (page >= BOOT_REGION_SIZE / PRV_PAGE) {
        return KM_FLASH_ERR_ALIGN;
    }
    km_bootb_watchdog_kick(); /* 25 erases of 40 ms outlast the 512 ms watchdog */
    prv_unlock();
    const uint32_t pnb = (BOOT_REGION_BASE - FLASH_MAIN_BASE) / PRV_PAGE + page;
    FLASH_CR = FLASH_CR_PER | (pnb << FLASH_CR_PNB_SHIFT);
    FLASH_CR |= FLASH_CR_STRT;
    return prv_done() ? KM_FLASH_OK : KM_FLASH_ERR_ERASE; /* the state machine blank-checks */
}

static km_flash_result_t prv_program(void *ctx, uint32_t off, const void *data, uint32_t n)
{
    (void)ctx;
    if (off % PRV_CELL != 0u || n % PRV_CELL != 0u || off > BOOT_REGION_SIZE || n > BOOT_REGION_SIZE - off) {
        return KM_FLASH_ERR_ALIGN;
    }
    const uint8_t *src = data;
    for (uint32_t i = 0; i < n; i += PRV_CELL) {
        volatile uint32_t *dst = (volatile uint32_t *)(uintptr_t)(BOOT_REGION_BASE + off + i);
        uint32_t w[2];
        memcpy(w, src + i, sizeof w);
        prv_unlock();
        FLASH_CR = FLASH_CR_PG;
        dst[0] = w[0];
        dst[1] = w[1];
        if (!prv_done()) {
            return KM_FLASH_ERR_PROGRAM; /* PROGERR: the cell was not erased */
        }
    }
    return KM_FLASH_OK; /* the state machine reads back */
}

/* Reads `n` bytes at base + off; a double ECC error (the NMI counted it)
 * makes the data untrustworthy. */
static km_flash_result_t prv_read_at(uint32_t base, uint32_t size, uint32_t off, void *data, uint32_t n)
{
    if (off > size || n > size - off) {
        return KM_FLASH_ERR_ALIGN;
    }
    const uint32_t before = km_boot_ecc_errors;
    const volatile uint8_t *src = (const volatile uint8_t *)(uintptr_t)(base + off);
    uint8_t *dst = data;
    for (uint32_t i = 0; i < n; i++) {
        dst[i] = src[i];
    }
    /* The NMI handler (boot_startup.c) counts a double ECC error during
     * the loop above: the volatile counter changes behind this code. */
    // cppcheck-suppress knownConditionTrueFalse
    return km_boot_ecc_errors == before ? KM_FLASH_OK : KM_FLASH_ERR_ECC;
}

static km_flash_result_t prv_read(void *ctx, uint32_t off, void *data, uint32_t n)
{
    (void)ctx;
    return prv_read_at(BOOT_REGION_BASE, BOOT_REGION_SIZE, off, data, n);
}

static km_flash_result_t prv_store_read(void *ctx, uint32_t off, void *data, uint32_t n)
{
    (void)ctx;
    return prv_read_at(BOOT_STORE_BASE, BOOT_STORE_SIZE, off, data, n);
}

/* The bootloader only mounts the store: it never erases or programs it. */
static km_flash_result_t prv_store_refuse(void *ctx, uint32_t page)
{
    (void)ctx;
    (void)page;
    return KM_FLASH_ERR_ERASE;
}

static km_flash_result_t prv_store_refuse_program(void *ctx, uint32_t off, const void *d, uint32_t n)
{
    (void)ctx;
    (void)off;
    (void)d;
    (void)n;
    return KM_FLASH_ERR_PROGRAM;
}

static const km_flash_t k_region = {
    .page_size = PRV_PAGE,
    .prog_size = PRV_CELL,
    .page_count = BOOT_REGION_SIZE / PRV_PAGE,
    .erase = prv_erase,
    .program = prv_program,
    .read = prv_read,
    .ctx = 0,
};

static const km_flash_t k_store = {
    .page_size = PRV_PAGE,
    .prog_size = PRV_CELL,
    .page_count = BOOT_STORE_SIZE / PRV_PAGE,
    .erase = prv_store_refuse,
    .program = prv_store_refuse_program,
    .read = prv_store_read,
    .ctx = 0,
};

const km_flash_t *km_bootb_region(void)
{
    return &k_region;
}

const km_flash_t *km_bootb_store(void)
{
    return &k_store;
}

const km_image_target_t *km_bootb_target(void)
{
    static const km_image_target_t k_target = {KM_MODEL_STM32G031, BOOT_REGION_BASE, BOOT_REGION_SIZE};
    return &k_target;
}

/* ---- USART1, single wire, polled ------------------------------------------ */

bool km_bootb_uart_init(uint32_t baud)
{
    if (baud < 9600u || baud > 1000000u) {
        return false;
    }
    /* Whole-register writes: the bootloader is the first code after reset
     * and uses no other pin of port B, whose reset state is every pin
     * analog, push-pull, no pull, AF0 (RM0444 §7.4): open drain with
     * pull-up, alternate function AF0 (AFRL stays 0) on PB6 only. */
    RCC_IOPENR = RCC_IOPENR_GPIOB;
    RCC_APBENR2 = RCC_APBENR2_USART1;
    GPIO_OTYPER(PIN_BUS_PORT) = 1u << PIN_BUS_PIN;
    GPIO_PUPDR(PIN_BUS_PORT) = 1u << (2u * PIN_BUS_PIN);
    GPIO_MODER(PIN_BUS_PORT) =
        ~(1u << (2u * PIN_BUS_PIN)); /* 0b10 (AF) on the pin, 0b11 (analog) elsewhere */
    USART1_CR1 = 0u;
    USART1_CR3 = USART_CR3_HDSEL;
    USART1_BRR = (PRV_HSI_HZ + baud / 2u) / baud;
    USART1_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE;
    return true;
}

bool km_bootb_uart_rx(uint8_t *byte)
{
    const uint32_t isr = USART1_ISR;
    if ((isr & (USART_ISR_ORE | USART_ISR_FE | USART_ISR_NE | USART_ISR_PE)) != 0u) {
        USART1_ICR = USART_ICR_ORECF | USART_ICR_FECF | USART_ICR_NECF | USART_ICR_PECF;
    }
    if ((isr & USART_ISR_RXNE) == 0u) {
        return false;
    }
    *byte = (uint8_t)USART1_RDR;
    return true;
}

#ifdef BOOT_HAS_WAIT
#define PRV_WAKE_US 10000u
#define PRV_WAKE_IRQS ((1u << G0_IRQ_TIM2) | (1u << G0_IRQ_USART1))

/* Sleeps until USART1's RXNE or a TIM2 CC1 10 ms ahead pends, PRIMASK set:
 * wakes, never taken (ARMv6-M B1.5.19; docs/update.md §6). */
void km_bootb_wait(void)
{
    __asm__ volatile("cpsid i" ::: "memory");
    TIM_CCR1(TIM2_BASE_R) = TIM_CNT(TIM2_BASE_R) + PRV_WAKE_US;
    TIM_SR(TIM2_BASE_R) = 0u;
    TIM_DIER(TIM2_BASE_R) = TIM_DIER_CC1IE;
    USART1_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;
    NVIC_ISER = PRV_WAKE_IRQS;
    __asm__ volatile("wfi" ::: "memory");
    NVIC_ICER = PRV_WAKE_IRQS;
    USART1_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE;
    TIM_DIER(TIM2_BASE_R) = 0u;
    NVIC_ICPR = PRV_WAKE_IRQS;
}
#endif

void km_bootb_uart_tx(const uint8_t *p, uint32_t n)
{
    /* Half duplex: the receiver would hear our own bytes; off while sending. */
    USART1_CR1 = USART_CR1_UE | USART_CR1_TE;
    for (uint32_t i = 0; i < n; i++) {
        while ((USART1_ISR & USART_ISR_TXE) == 0u) {
        }
        USART1_TDR = p[i];
    }
    while ((USART1_ISR & USART_ISR_TC) == 0u) {
    }
    USART1_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE;
}

/* ---- leaving ------------------------------------------------------------ */

_Noreturn void km_bootb_reset(void)
{
    __asm__ volatile("dsb" ::: "memory");
    SCB_AIRCR = 0x05FA0004u;
    for (;;) {
    }
}

void km_bootb_watchdog_kick(void)
{
    IWDG_KR = IWDG_KEY_KICK;
}

/* The IWDG for the image's trial (docs/update.md §3a): prescaler /4 and
 * the largest reload, 4096 x 4 / 32 kHz = 512 ms; the application's
 * km_hal_watchdog_start sets its own prescaler and reload on the running
 * watchdog (RM0444 §27.3: PR and RLR stay writable after the start; their
 * update is done when PVU and RVU read 0, waited for here so the
 * application's first write is taken). */
static void prv_watchdog_start(void)
{
    IWDG_KR = IWDG_KEY_START;
    IWDG_KR = IWDG_KEY_UNLOCK;
    IWDG_PR = 0u;
    IWDG_RLR = 0xFFFu;
    while (IWDG_SR != 0u) {
    }
    IWDG_KR = IWDG_KEY_KICK;
}

_Noreturn void km_bootb_start(uint32_t vectors, uint32_t sp, uint32_t pc)
{
    km_bootb_shared()->app_running = KM_BOOT_APP_MAGIC;
    prv_watchdog_start();
#if KM_IMAGE_VECTORS % 256u == 0u
    PRV_SCB_VTOR = vectors;
#else
    (void)vectors; /* not 256-aligned: the application's startup sets VTOR (docs/update.md §2) */
#endif
    __asm__ volatile("dsb         \n"
                     "isb         \n"
                     "msr msp, %0 \n"
                     "bx  %1      \n"
                     :
                     : "r"(sp), "r"(pc)
                     : "memory");
    for (;;) {
    }
}
