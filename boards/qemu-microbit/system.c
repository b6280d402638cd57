/* System services (km_hal_system.h) on the nRF51: clocks, reset, watchdog,
 * interrupt lock, entropy, idle. */
#include "km_cortex_m.h"
#include "km_hal_system.h"
#include "km_hal_time.h"
#include "nrf51_regs.h"

#define PRV_WDT_CLK_HZ 32768u
#define PRV_RNG_BYTE_US 2000u      /* a real (and QEMU's) bias-corrected byte takes ~0.7 ms */
#define PRV_RNG_SPINS 2000000u     /* last resort if TIMER0 is not running yet */
#define PRV_SYSTICK_RELOAD (NRF_HFCLK_HZ / 1000u - 1u)

void km_hal_system_init(void)
{
    /* The UART baud and the 1 MHz tick are only as good as HFCLK: start the
     * 16 MHz crystal (QEMU's CLOCK stub reads 1 for every event, so this
     * returns at once there). */
    NRF_REG(NRF_CLOCK, CLOCK_EVENTS_HFCLKSTARTED) = 0u;
    NRF_REG(NRF_CLOCK, CLOCK_TASKS_HFCLKSTART) = 1u;
    while (NRF_REG(NRF_CLOCK, CLOCK_EVENTS_HFCLKSTARTED) == 0u) {
    }
    /* SysTick runs at 1 kHz: QEMU only re-polls the UART
     * socket promptly while a guest timer is active (DESIGN.md). TIMER0's
     * pending compare already keeps one active (echo round trip measured
     * 1.2 ms median without SysTick, 0.95 ms with), so this is a cheap
     * belt-and-braces. A real nRF51 has no SysTick: the writes are ignored. */
    NRF_REG(SCS_SYST_RVR, 0) = PRV_SYSTICK_RELOAD;
    NRF_REG(SCS_SYST_CVR, 0) = 0u;
    /* Its interrupt is the 1 kHz wake-up km_hal_idle() promises (hal
     * contract), so WFI never sleeps through a control tick. */
    NRF_REG(SCS_SYST_CSR, 0) = (1u << 2) | (1u << 1) | (1u << 0); /* CPU clock, TICKINT, enable */
}

/* Only wakes the core from WFI: the main loop reads the time itself. */
void SysTick_Handler(void)
{
}

_Noreturn void km_hal_system_reset(void)
{
    __asm__ volatile("dsb" ::: "memory");
    NRF_REG(SCS_AIRCR, 0) = AIRCR_VECTKEY | AIRCR_SYSRESETREQ;
    __asm__ volatile("dsb" ::: "memory");
    for (;;) {
    }
}

/* Not modelled by QEMU 7.2 (the WDT range is an "unimplemented device": writes
 * are ignored), so in QEMU this never bites; the code is for the real part. */
void km_hal_watchdog_start(uint32_t timeout_ms)
{
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

/* Four RNG bytes mixed with FICR DEVICEID. QEMU's FICR holds the same
 * DEVICEID for every instance (0x12345678 0x9ABCDEF1), so on QEMU the RNG is
 * what makes servos differ. The wait is bounded in time, not in loop turns:
 * QEMU runs a loop turn far faster than 16 MHz silicon while its RNG still
 * takes 660 us of virtual time per byte. */
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
    /* WFI wakes on any pending enabled interrupt even under the irq lock
     * (PRIMASK set), so callers may check-then-sleep inside a lock without
     * losing a wake-up; the handler then runs after their restore. */
    km_cortex_wait_for_interrupt();
}
