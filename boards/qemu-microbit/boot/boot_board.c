/* SPDX-License-Identifier: Apache-2.0 */
/* The bootloader's board part for the nRF51 (km_boot_board.h): HFCLK and
 * TIMER0 at 1 MHz, UART0 polled, the NVMC over the application region,
 * the start on trial (WDT and the TIMER2 trial timer, docs/update.md §3a),
 * and QEMU's factory slot (docs/update.md §6). The store region is
 * boards/qemu-microbit/flash.c's, the driver the application uses. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "boot_layout.h"
#include "km_boot_board.h"
#include "km_boot_check.h"
#include "km_board.h"
#include "km_crc32.h"
#include "km_update.h"
#include "nrf51_regs.h"

#define PRV_CELL 4u
#define PRV_PIN_TXD 24u
#define PRV_PIN_RXD 25u

/* boot_startup.c's stubs read these two words by address. */
_Static_assert(BOOT_SHARED_ADDR + offsetof(km_boot_shared_t, app_running) == BOOT_APP_RUNNING_ADDR,
               "app_running address");
_Static_assert(BOOT_SHARED_ADDR + offsetof(km_boot_shared_t, confirmed) == BOOT_CONFIRMED_ADDR,
               "confirmed address");
_Static_assert(BOOT_APP_MAGIC_WORD == KM_BOOT_APP_MAGIC && BOOT_CONFIRMED_WORD == KM_BOOT_CONFIRMED_MAGIC,
               "magic words");
_Static_assert(BOOT_SHARED_ADDR + sizeof(km_boot_shared_t) == 0x20004000, "the top of RAM");

volatile km_boot_shared_t *km_bootb_shared(void)
{
    return (volatile km_boot_shared_t *)(uintptr_t)BOOT_SHARED_ADDR;
}

void km_bootb_init(void)
{
    NRF_REG(NRF_CLOCK, CLOCK_EVENTS_HFCLKSTARTED) = 0u;
    NRF_REG(NRF_CLOCK, CLOCK_TASKS_HFCLKSTART) = 1u;
    while (NRF_REG(NRF_CLOCK, CLOCK_EVENTS_HFCLKSTARTED) == 0u) {
    }
    NRF_REG(NRF_TIMER0, TIMER_TASKS_STOP) = 1u;
    NRF_REG(NRF_TIMER0, TIMER_MODE) = 0u;
    NRF_REG(NRF_TIMER0, TIMER_BITMODE) = TIMER_BITMODE_32;
    NRF_REG(NRF_TIMER0, TIMER_PRESCALER) = 4u; /* 16 MHz >> 4 */
    NRF_REG(NRF_TIMER0, TIMER_TASKS_CLEAR) = 1u;
    NRF_REG(NRF_TIMER0, TIMER_TASKS_START) = 1u;
}

uint32_t km_bootb_now_us(void)
{
    NRF_REG(NRF_TIMER0, TIMER_TASKS_CAPTURE(0)) = 1u;
    return NRF_REG(NRF_TIMER0, TIMER_CC(0));
}

#define PRV_UART0_IRQ 2u
#define PRV_TIMER0_IRQ 8u
#define PRV_WAKE_US 10000u

/* WFI until UART0's RXDRDY or TIMER0's COMPARE1 (now + 10 ms) pends its
 * interrupt: both are enabled at the peripheral and in the NVIC only
 * around the WFI, with PRIMASK set, so the core wakes but never takes
 * them (the vector stubs would reset: boot_startup.c). */
void km_bootb_wait(void)
{
    __asm__ volatile("cpsid i" ::: "memory");
    NRF_REG(NRF_TIMER0, TIMER_CC(1)) = km_bootb_now_us() + PRV_WAKE_US;
    NRF_REG(NRF_TIMER0, TIMER_EVENTS_COMPARE(1)) = 0u;
    NRF_REG(NRF_TIMER0, TIMER_INTENSET) = TIMER_INT_COMPARE(1);
    NRF_REG(NRF_UART0, UART_INTENSET) = UART_INT_RXDRDY;
    nrf_irq_enable(PRV_TIMER0_IRQ);
    nrf_irq_enable(PRV_UART0_IRQ);
    if (NRF_REG(NRF_UART0, UART_EVENTS_RXDRDY) == 0u) {
        __asm__ volatile("wfi" ::: "memory");
    }
    nrf_irq_disable(PRV_UART0_IRQ);
    nrf_irq_disable(PRV_TIMER0_IRQ);
}

uint32_t km_bootb_hw_version(void)
{
    return 0x10u;
}

/* ---- the application region on the NVMC -------------------------------- */

static void prv_ready(void)
{
    while (NRF_REG(NRF_NVMC, NVMC_READY) == 0u) {
    }
}

static void prv_mode(uint32_t mode)
{
    NRF_REG(NRF_NVMC, NVMC_CONFIG) = mode;
    prv_ready();
}

static bool prv_inside(uint32_t off, uint32_t n)
{
    return off <= BOOT_REGION_SIZE && n <= BOOT_REGION_SIZE - off;
}

static km_flash_result_t prv_erase(void *ctx, uint32_t page)
{
    (void)ctx;
    if (page >= BOOT_REGION_SIZE / BOOT_PAGE) {
        return KM_FLASH_ERR_ALIGN;
    }
    km_bootb_watchdog_kick(); /* 112 erases of 21 ms outlast the 500 ms watchdog */
    prv_mode(NVMC_CONFIG_EEN);
    NRF_REG(NRF_NVMC, NVMC_ERASEPAGE) = BOOT_REGION_BASE + page * BOOT_PAGE;
    prv_ready();
    prv_mode(NVMC_CONFIG_REN);
    return KM_FLASH_OK; /* the state machine blank-checks */
}

static km_flash_result_t prv_program(void *ctx, uint32_t off, const void *data, uint32_t n)
{
    (void)ctx;
    if (off % PRV_CELL != 0u || n % PRV_CELL != 0u || !prv_inside(off, n)) {
        return KM_FLASH_ERR_ALIGN;
    }
    const uint8_t *src = data;
    for (uint32_t i = 0; i < n; i += PRV_CELL) {
        volatile uint32_t *cell = (volatile uint32_t *)(uintptr_t)(BOOT_REGION_BASE + off + i);
        if (*cell != 0xFFFFFFFFu) {
            return KM_FLASH_ERR_PROGRAM; /* only onto erased cells */
        }
        uint32_t w;
        memcpy(&w, src + i, sizeof w);
        prv_mode(NVMC_CONFIG_WEN);
        *cell = w;
        prv_ready();
        prv_mode(NVMC_CONFIG_REN);
    }
    return KM_FLASH_OK; /* the state machine reads back */
}

static km_flash_result_t prv_read(void *ctx, uint32_t off, void *data, uint32_t n)
{
    const uint32_t base = (uint32_t)(uintptr_t)ctx;
    if (!prv_inside(off, n)) {
        return KM_FLASH_ERR_ALIGN;
    }
    memcpy(data, (const void *)(uintptr_t)(base + off), n);
    return KM_FLASH_OK;
}

static const km_flash_t k_region = {
    .page_size = BOOT_PAGE,
    .prog_size = PRV_CELL,
    .page_count = BOOT_REGION_SIZE / BOOT_PAGE,
    .erase = prv_erase,
    .program = prv_program,
    .read = prv_read,
    .ctx = (void *)(uintptr_t)BOOT_REGION_BASE,
};

const km_flash_t *km_bootb_region(void)
{
    return &k_region;
}

const km_flash_t *km_bootb_store(void)
{
    return km_board_flash();
}

const km_image_target_t *km_bootb_target(void)
{
    static const km_image_target_t k_target = {KM_MODEL_QEMU_MICROBIT, BOOT_REGION_BASE, BOOT_REGION_SIZE};
    return &k_target;
}

/* ---- QEMU's factory slot (docs/update.md §6) ---------------------------- */

/* The factory programmer's stand-in: a region whose first cell reads 00
 * was never written (QEMU's flash outside the loaded blobs; an erased part
 * reads FF), so the image in the factory slot is installed with an update
 * session of its own: the same checks, order and commit cell. */
void km_bootb_factory(void)
{
    static km_update_t s_upd;
    static const km_flash_t k_slot = {
        .page_size = BOOT_PAGE,
        .prog_size = PRV_CELL,
        .page_count = BOOT_REGION_SIZE / BOOT_PAGE,
        .erase = prv_erase,
        .program = prv_program,
        .read = prv_read,
        .ctx = (void *)(uintptr_t)BOOT_FACTORY_BASE,
    };
    if (*(const volatile uint32_t *)(uintptr_t)BOOT_REGION_BASE != 0u ||
        !km_boot_check(&k_slot, km_bootb_target(), NULL)) {
        return;
    }
    km_update_init(&s_upd, &k_region, km_bootb_target());
    const uint8_t *img = (const uint8_t *)(uintptr_t)BOOT_FACTORY_BASE;
    if (km_update_begin(&s_upd, img) != KM_UPD_OK) {
        return;
    }
    for (uint32_t b = 0; b < s_upd.blocks; b++) {
        const uint8_t *blk = img + b * KM_UPDATE_BLOCK;
        if (km_update_write(&s_upd, b, blk, km_crc32(0u, blk, KM_UPDATE_BLOCK)) != KM_UPD_OK) {
            return;
        }
    }
    uint32_t crc;
    if (km_update_verify(&s_upd, &crc) == KM_UPD_OK) {
        (void)km_update_commit(&s_upd);
    }
}

/* ---- UART0, polled -------------------------------------------------------- */

bool km_bootb_uart_init(uint32_t baud)
{
    if (baud < 1200u || baud > 1000000u) {
        return false;
    }
    const uint32_t reg = (uint32_t)(((uint64_t)baud << 32) / 16000000u) & ~0xFFFu;
    NRF_REG(NRF_UART0, UART_ENABLE) = 0u;
    NRF_REG(NRF_UART0, UART_PSELTXD) = PRV_PIN_TXD;
    NRF_REG(NRF_UART0, UART_PSELRXD) = PRV_PIN_RXD;
    NRF_REG(NRF_UART0, UART_PSELRTS) = UART_PSEL_DISCONNECTED;
    NRF_REG(NRF_UART0, UART_PSELCTS) = UART_PSEL_DISCONNECTED;
    NRF_REG(NRF_UART0, UART_CONFIG) = 0u;
    NRF_REG(NRF_UART0, UART_BAUDRATE) = reg;
    NRF_REG(NRF_UART0, UART_ENABLE) = UART_ENABLE_ENABLED;
    NRF_REG(NRF_UART0, UART_EVENTS_RXDRDY) = 0u;
    NRF_REG(NRF_UART0, UART_TASKS_STARTRX) = 1u;
    NRF_REG(NRF_UART0, UART_TASKS_STARTTX) = 1u;
    return true;
}

bool km_bootb_uart_rx(uint8_t *byte)
{
    if (NRF_REG(NRF_UART0, UART_EVENTS_ERROR) != 0u) {
        NRF_REG(NRF_UART0, UART_EVENTS_ERROR) = 0u;
        NRF_REG(NRF_UART0, UART_ERRORSRC) = 0xFu;
    }
    if (NRF_REG(NRF_UART0, UART_EVENTS_RXDRDY) == 0u) {
        return false;
    }
    NRF_REG(NRF_UART0, UART_EVENTS_RXDRDY) = 0u;
    *byte = (uint8_t)NRF_REG(NRF_UART0, UART_RXD);
    return true;
}

void km_bootb_uart_tx(const uint8_t *p, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++) {
        NRF_REG(NRF_UART0, UART_EVENTS_TXDRDY) = 0u;
        NRF_REG(NRF_UART0, UART_TXD) = p[i];
        while (NRF_REG(NRF_UART0, UART_EVENTS_TXDRDY) == 0u) {
        }
    }
}

/* ---- leaving ------------------------------------------------------------ */

_Noreturn void km_bootb_reset(void)
{
    __asm__ volatile("dsb" ::: "memory");
    NRF_REG(SCS_AIRCR, 0) = AIRCR_VECTKEY | AIRCR_SYSRESETREQ;
    __asm__ volatile("dsb" ::: "memory");
    for (;;) {
    }
}

void km_bootb_watchdog_kick(void)
{
    NRF_REG(NRF_WDT, WDT_RR0) = WDT_RR_RELOAD;
}

/* The watchdog on silicon (QEMU 7.2 ignores it): the application's own
 * settings, which its km_hal_watchdog_start cannot change once it runs. */
static void prv_watchdog_start(void)
{
    NRF_REG(NRF_WDT, WDT_CONFIG) = WDT_CONFIG_SLEEP_RUN | WDT_CONFIG_HALT_PAUSE;
    NRF_REG(NRF_WDT, WDT_CRV) = BOOT_WDT_MS * 32768u / 1000u;
    NRF_REG(NRF_WDT, WDT_RREN) = 1u;
    NRF_REG(NRF_WDT, WDT_TASKS_START) = 1u;
}

/* The trial timer (docs/update.md §3a): TIMER2's COMPARE0 interrupt after
 * 2 s, taken by boot_startup.c's km_boot_trial, which resets unless the
 * application has confirmed (and stopped this timer) by then. */
static void prv_trial_timer_start(void)
{
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_TASKS_STOP) = 1u;
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_MODE) = 0u;
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_BITMODE) = TIMER_BITMODE_16;
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_PRESCALER) = BOOT_TRIAL_PRESCALER;
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_SHORTS) = 0u;
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_CC(0)) = BOOT_TRIAL_TICKS;
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_EVENTS_COMPARE(0)) = 0u;
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_INTENSET) = TIMER_INT_COMPARE(0);
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_TASKS_CLEAR) = 1u;
    nrf_irq_enable(BOOT_TRIAL_IRQ);
    NRF_REG(BOOT_TRIAL_TIMER, TIMER_TASKS_START) = 1u;
}

_Noreturn void km_bootb_start(uint32_t vectors, uint32_t sp, uint32_t pc)
{
    (void)vectors; /* no VTOR: boot_startup.c forwards to BOOT_APP_VECTORS */
    km_bootb_shared()->app_running = KM_BOOT_APP_MAGIC;
    prv_watchdog_start();
    prv_trial_timer_start();
    __asm__ volatile("msr msp, %0 \n"
                     "bx  %1      \n"
                     :
                     : "r"(sp), "r"(pc)
                     : "memory");
    for (;;) {
    }
}
