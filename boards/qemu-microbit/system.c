/* SPDX-License-Identifier: Apache-2.0 */
/* System services (km_hal_system.h) on the nRF51: clocks, reset, watchdog,
 * interrupt lock, entropy, idle; the reset cause (a .noinit record, then
 * RESETREAS) and the HardFault handler (docs/architecture.md "qemu-microbit's
 * system services"). */
#include <stdbool.h>

#include "km_cortex_m.h"
#include "km_hal_system.h"
#include "km_hal_time.h"
#include "nrf51_regs.h"

#define PRV_WDT_CLK_HZ 32768u
#define PRV_RNG_BYTE_US 2000u  /* a real (and QEMU's) bias-corrected byte takes ~0.7 ms */
#define PRV_RNG_SPINS 2000000u /* last resort if TIMER0 is not running yet */
#define PRV_SYSTICK_RELOAD (NRF_HFCLK_HZ / 1000u - 1u)

/* POWER shares the peripheral slot (ID 0) with CLOCK (nRF51 RM §12). */
#define PRV_POWER_RESETREAS 0x400u
#define PRV_RESETREAS_RESETPIN (1u << 0)
#define PRV_RESETREAS_DOG (1u << 1)
#define PRV_RESETREAS_SREQ (1u << 2)
#define PRV_RESETREAS_LOCKUP (1u << 3)
#define PRV_RESETREAS_WAKE (7u << 16) /* OFF, LPCOMP, DIF: wake-up from System OFF */

#define PRV_NOTE_MAGIC 0x5E7CA05Eu

/* The cause of a reset this firmware makes itself, kept in .noinit for the next boot. */
typedef struct {
    uint32_t magic;
    uint32_t cause; /* KM_RESET_SOFTWARE or KM_RESET_FAULT */
    uint32_t pc;    /* the faulting instruction (stacked PC), 0 for a restart */
    uint32_t check;
} prv_reset_note_t;

static volatile prv_reset_note_t s_note __attribute__((section(".noinit")));
static km_reset_cause_t s_cause;

/* The previous run's fault address, for a debugger; 0 unless the last reset was a fault. */
uint32_t km_board_last_fault_pc;

void km_board_reset_capture(void);
_Noreturn void km_board_fault_stop(uint32_t pc);

static void prv_note(uint32_t cause, uint32_t pc)
{
    s_note.cause = cause;
    s_note.pc = pc;
    s_note.check = ~(PRV_NOTE_MAGIC ^ cause ^ pc);
    s_note.magic = PRV_NOTE_MAGIC;
}

/* Reads the reset cause once at boot: the record first, then RESETREAS. */
void km_board_reset_capture(void)
{
    uint32_t reas = NRF_REG(NRF_CLOCK, PRV_POWER_RESETREAS);
    NRF_REG(NRF_CLOCK, PRV_POWER_RESETREAS) = reas; /* write 1s: clear what was read */
    if (reas != 0u && NRF_REG(NRF_CLOCK, PRV_POWER_RESETREAS) == reas) {
        reas = 0u; /* did not clear: QEMU's stub, not a real register */
    }

    bool noted = s_note.magic == PRV_NOTE_MAGIC &&
                 s_note.check == ~(s_note.magic ^ s_note.cause ^ s_note.pc) &&
                 (s_note.cause == KM_RESET_SOFTWARE || s_note.cause == KM_RESET_FAULT);
    s_note.magic = 0u;

    if (noted) {
        s_cause = (km_reset_cause_t)s_note.cause;
        km_board_last_fault_pc = s_cause == KM_RESET_FAULT ? s_note.pc : 0u;
    } else if ((reas & PRV_RESETREAS_LOCKUP) != 0u) {
        s_cause = KM_RESET_FAULT; /* a fault inside the fault handler: the core locked up */
    } else if ((reas & PRV_RESETREAS_DOG) != 0u) {
        s_cause = KM_RESET_WATCHDOG;
    } else if ((reas & PRV_RESETREAS_SREQ) != 0u) {
        s_cause = KM_RESET_SOFTWARE;
    } else if ((reas & PRV_RESETREAS_RESETPIN) != 0u) {
        s_cause = KM_RESET_PIN;
    } else if ((reas & PRV_RESETREAS_WAKE) != 0u) {
        s_cause = KM_RESET_OTHER;
    } else {
        s_cause = KM_RESET_POWER_ON; /* power-on and brown-out set no bit on the nRF51 */
    }
}

km_reset_cause_t km_hal_reset_cause(void)
{
    return s_cause;
}

static _Noreturn void prv_sysresetreq(void)
{
    __asm__ volatile("dsb" ::: "memory");
    NRF_REG(SCS_AIRCR, 0) = AIRCR_VECTKEY | AIRCR_SYSRESETREQ;
    __asm__ volatile("dsb" ::: "memory");
    for (;;) {
    }
}

/* The fault path's C part, on a fresh stack: record the fault, reset at once. */
_Noreturn void km_board_fault_stop(uint32_t pc)
{
    prv_note(KM_RESET_FAULT, pc);
    prv_sysresetreq();
}

/* HardFault and every unexpected vector: the stacked PC, then a fresh stack for the C part. */
__attribute__((naked)) void HardFault_Handler(void)
{
    __asm__ volatile("movs r0, #4                \n"
                     "mov  r1, lr                \n"
                     "tst  r0, r1                \n"
                     "bne  1f                    \n"
                     "mrs  r1, msp               \n"
                     "b    2f                    \n"
                     "1:                         \n"
                     "mrs  r1, psp               \n"
                     "2:                         \n"
                     "ldr  r0, [r1, #24]         \n"
                     "ldr  r1, =__stack_top      \n"
                     "mov  sp, r1                \n"
                     "ldr  r1, =km_board_fault_stop\n"
                     "bx   r1                    \n");
}

void km_hal_system_init(void)
{
    /* Start the 16 MHz crystal (HFCLK). */
    NRF_REG(NRF_CLOCK, CLOCK_EVENTS_HFCLKSTARTED) = 0u;
    NRF_REG(NRF_CLOCK, CLOCK_TASKS_HFCLKSTART) = 1u;
    while (NRF_REG(NRF_CLOCK, CLOCK_EVENTS_HFCLKSTARTED) == 0u) {
    }
    /* SysTick at 1 kHz: QEMU's prompt UART polling, and km_hal_idle()'s wake-up. */
    NRF_REG(SCS_SYST_RVR, 0) = PRV_SYSTICK_RELOAD;
    NRF_REG(SCS_SYST_CVR, 0) = 0u;
    NRF_REG(SCS_SYST_CSR, 0) = (1u << 2) | (1u << 1) | (1u << 0); /* CPU clock, TICKINT, enable */
}

/* Wakes the core and km_hal_sleep(): the main loop reads the time itself. */
void SysTick_Handler(void)
{
    km_cortex_wake();
}

/* Leaves the SOFTWARE record, then resets the MCU. */
_Noreturn void km_hal_system_reset(void)
{
    prv_note(KM_RESET_SOFTWARE, 0u);
    prv_sysresetreq();
}

/* Starts the watchdog unless it already runs, then only kicked (nRF51 RM §25, docs/update.md §3a). */
void km_hal_watchdog_start(uint32_t timeout_ms)
{
    if ((NRF_REG(NRF_WDT, WDT_RUNSTATUS) & 1u) != 0u) {
        km_hal_watchdog_kick();
        return;
    }
    uint64_t ticks = (uint64_t)timeout_ms * PRV_WDT_CLK_HZ / 1000u;
    if (ticks < 15u) {
        ticks = 15u; /* RM: CRV minimum is 15 */
    }
    if (ticks > 0xFFFFFFFFu) {
        ticks = 0xFFFFFFFFu;
    }
    NRF_REG(NRF_WDT, WDT_CONFIG) = WDT_CONFIG_SLEEP_RUN | WDT_CONFIG_HALT_PAUSE;
    NRF_REG(NRF_WDT, WDT_CRV) = (uint32_t)ticks;
    NRF_REG(NRF_WDT, WDT_RREN) = 1u; /* only RR[0] reloads */
    NRF_REG(NRF_WDT, WDT_TASKS_START) = 1u;
}

void km_hal_watchdog_kick(void)
{
    NRF_REG(NRF_WDT, WDT_RR0) = WDT_RR_RELOAD;
}

uint32_t km_hal_irq_lock(void)
{
    return km_cortex_irq_lock();
}

void km_hal_irq_restore(uint32_t state)
{
    km_cortex_irq_restore(state);
}

/* Four RNG bytes mixed with FICR DEVICEID, each wait bounded in time. */
uint32_t km_hal_entropy(void)
{
    uint32_t value = NRF_REG(NRF_FICR, FICR_DEVICEID0) ^ NRF_REG(NRF_FICR, FICR_DEVICEID1);
    NRF_REG(NRF_RNG, RNG_CONFIG) = 1u; /* bias correction */
    NRF_REG(NRF_RNG, RNG_EVENTS_VALRDY) = 0u;
    NRF_REG(NRF_RNG, RNG_TASKS_START) = 1u;
    for (uint32_t i = 0; i < 4u; i++) {
        uint32_t spins = PRV_RNG_SPINS;
        uint32_t start = km_hal_time_now();
        while (NRF_REG(NRF_RNG, RNG_EVENTS_VALRDY) == 0u && spins > 0u &&
               km_hal_time_now() - start < PRV_RNG_BYTE_US) {
            spins--;
        }
        NRF_REG(NRF_RNG, RNG_EVENTS_VALRDY) = 0u;
        value ^= (NRF_REG(NRF_RNG, RNG_VALUE) & 0xFFu) << (8u * i);
    }
    NRF_REG(NRF_RNG, RNG_TASKS_STOP) = 1u;
    return value;
}

void km_hal_idle(void)
{
    /* WFI wakes on a pending interrupt even under the irq lock (PRIMASK). */
    km_cortex_wait_for_interrupt();
}

/* Sleep-on-exit; an emulator that ignores SLEEPONEXIT makes it return early. */
void km_hal_sleep(uint32_t state)
{
    km_cortex_sleep_until_wake(state);
}

void km_hal_wake(void)
{
    km_cortex_wake();
}
