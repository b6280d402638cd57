/* SPDX-License-Identifier: Apache-2.0 */
/* Faults, reset cause and stack guard of the STM32G031 board.
 *
 * A HardFault (and any vector nothing should raise, which startup.c sends
 * here too) frees the H-bridge, writes a record to .noinit RAM and resets at
 * once with SYSRESETREQ. Why not park and let the IWDG bite: the bridge would
 * keep whatever PWM it had for up to the watchdog timeout (500 ms of a motor
 * driving into an end stop), and a fault before the watchdog is started
 * would hang for ever. Why free the bridge first, although the reset that
 * follows puts the pins back to analog (the driver's pull-downs then coast
 * it): the few register writes make the bridge safe within a microsecond
 * even if the reset were held off (a debugger attached, SYSRESETREQ masked by
 * a future change); everything after that is bookkeeping.
 *
 * The handler path must not fault again (a fault inside the HardFault
 * handler locks the core up, and only the IWDG ends a lockup): it uses no hal
 * calls and only register writes, and it moves SP to the top of the stack
 * region before any C runs, because the stack running out is one of the
 * faults it handles.
 *
 * The reset cause is captured once per boot from Reset_Handler, before
 * main(): RCC_CSR is read, its flags cleared with RMVF so the next reset
 * reads fresh, the fault record read and cleared, and reset_cause.c maps the
 * lot to km_reset_cause_t. */
#include "fault.h"

#include "board_pins.h"
#include "g0_regs.h"
#include "g0_vectors.h"
#include "km_hal_system.h"
#include "reset_cause.h"

/* Linker script symbols (stm32g031.ld): the stack region at the bottom of
 * SRAM, its guard band the lowest KM_STACK_GUARD bytes of it. */
extern uint32_t __stack_limit[], __stack_guard_end[], _estack[];

#define PRV_FAULT_MAGIC 0xFA017EC0u
#define PRV_ALIVE_MAGIC 0xA11FE5A5u
#define PRV_STACK_PAINT 0x5AFE57ACu
/* The reset handler's own frame (and g0_stack_paint's) sits at the top of
 * the stack while it paints: leave that much unpainted. */
#define PRV_PAINT_SKIP_WORDS 64u

/* Written by the fault path just before SYSRESETREQ, read and cleared at the
 * next boot. .noinit: neither loaded nor zeroed by Reset_Handler, and SRAM
 * keeps its contents across a system reset. check = ~(magic ^ kind ^ pc ^
 * lr), so random power-up contents pass with odds of 2^-64. */
typedef struct {
    uint32_t magic;
    uint32_t kind; /* IPSR exception number (3 = HardFault), or G0_FAULT_STACK_GUARD */
    uint32_t pc;   /* stacked PC: the faulting instruction (0 for the guard) */
    uint32_t lr;   /* stacked LR: its caller, in most cases */
    uint32_t check;
} g0_fault_record_t;

static volatile g0_fault_record_t s_fault_record __attribute__((section(".noinit")));

/* Set at every boot; intact at the next one only if SRAM was never lost in
 * between (tells a brown-out from a power-up, see reset_cause.c). */
static volatile uint32_t s_alive[2] __attribute__((section(".noinit")));

static km_reset_cause_t s_cause;

/* The previous run's fault record, kept after the capture for a debugger
 * (`print g0_last_fault`): magic 0 if the last reset was no fault. */
g0_fault_record_t g0_last_fault;

void g0_stack_paint(void)
{
    uintptr_t end = (uintptr_t)_estack - 4u * PRV_PAINT_SKIP_WORDS;
    for (uint32_t *p = __stack_limit; (uintptr_t)p < end; p++) {
        *p = PRV_STACK_PAINT;
    }
}

/* The guard band's words one call checks: a quarter of its 32, in turn. */
#define PRV_GUARD_SLICE_WORDS 8u
static uint32_t s_guard_next; /* word offset of the slice checked next */

/* From RAM: SysTick calls it every millisecond, flash erases included. One
 * slice a call, so the whole band every 4 ms (docs/benchmarks.md "Control
 * tick"): paint once overwritten stays overwritten, so a stack that
 * reached the band is still seen. */
G0_RAMFUNC(g0_stack_guard_intact) bool g0_stack_guard_intact(void)
{
    const uint32_t band_words = (uint32_t)(__stack_guard_end - __stack_limit);
    const volatile uint32_t *p = __stack_limit + s_guard_next;
    _Static_assert(PRV_GUARD_SLICE_WORDS == 8u, "the slice is read as eight words");
    const uint32_t diff = (p[0] ^ PRV_STACK_PAINT) | (p[1] ^ PRV_STACK_PAINT) | (p[2] ^ PRV_STACK_PAINT) |
                          (p[3] ^ PRV_STACK_PAINT) | (p[4] ^ PRV_STACK_PAINT) | (p[5] ^ PRV_STACK_PAINT) |
                          (p[6] ^ PRV_STACK_PAINT) | (p[7] ^ PRV_STACK_PAINT);
    const uint32_t next = s_guard_next + PRV_GUARD_SLICE_WORDS;
    s_guard_next = next + PRV_GUARD_SLICE_WORDS <= band_words ? next : 0u;
    return diff == 0u;
}

void g0_reset_capture(void)
{
    uint32_t csr = RCC_CSR;
    RCC_CSR = csr | RCC_CSR_RMVF; /* keeps LSION; clears every reset flag */

    bool fault = s_fault_record.magic == PRV_FAULT_MAGIC &&
                 s_fault_record.check ==
                     ~(s_fault_record.magic ^ s_fault_record.kind ^ s_fault_record.pc ^ s_fault_record.lr);
    if (fault) {
        g0_last_fault.magic = s_fault_record.magic;
        g0_last_fault.kind = s_fault_record.kind;
        g0_last_fault.pc = s_fault_record.pc;
        g0_last_fault.lr = s_fault_record.lr;
        g0_last_fault.check = s_fault_record.check;
    }
    s_fault_record.magic = 0u;

    bool ram_kept = s_alive[0] == PRV_ALIVE_MAGIC && s_alive[1] == ~PRV_ALIVE_MAGIC;
    s_alive[0] = PRV_ALIVE_MAGIC;
    s_alive[1] = ~PRV_ALIVE_MAGIC;

    s_cause = g0_reset_cause_decode(csr, fault, ram_kept);
}

km_reset_cause_t km_hal_reset_cause(void)
{
    return s_cause;
}

/* Bridge to the free state (IN1 = IN2 = low: outputs high-Z, the motor
 * coasts) by taking both pins from TIM3 to plain GPIO outputs driven low:
 * ODR is cleared before MODER switches, so no pin ever goes high on the way.
 * The port clock is enabled in case the fault came before
 * km_hal_system_init() (the pins are then still analog, and this makes them
 * low outputs, which is the same state for the driver). TIM3's outputs are
 * disabled as well; with its clock still off those writes are ignored. */
static void prv_bridge_free(void)
{
    RCC_IOPENR |= RCC_IOPENR_GPIOA;
    GPIO_BRR(PIN_IN1_PORT) = 1u << PIN_IN1_PIN;
    GPIO_BRR(PIN_IN2_PORT) = 1u << PIN_IN2_PIN;
    GPIO_MODER(PIN_IN1_PORT) =
        (GPIO_MODER(PIN_IN1_PORT) & ~(3u << (2u * PIN_IN1_PIN))) | (1u << (2u * PIN_IN1_PIN));
    GPIO_MODER(PIN_IN2_PORT) =
        (GPIO_MODER(PIN_IN2_PORT) & ~(3u << (2u * PIN_IN2_PIN))) | (1u << (2u * PIN_IN2_PIN));
    TIM_CCER(TIM3_BASE_R) = 0u;
#ifdef KM_BOARD_RS485_DE
    /* Let go of the bus too: a fault mid-answer must not hold the line. */
    GPIO_BRR(PIN_DE_PORT) = 1u << PIN_DE_PIN;
#endif
}

/* Reached only through g0_fault_stop, with SP already at the top of the
 * stack region. `used`: the only reference is from the asm below. */
__attribute__((used, noreturn)) static void prv_fault_stop_c(uint32_t kind, uint32_t pc, uint32_t lr)
{
    prv_bridge_free();
    s_fault_record.kind = kind;
    s_fault_record.pc = pc;
    s_fault_record.lr = lr;
    s_fault_record.check = ~(PRV_FAULT_MAGIC ^ kind ^ pc ^ lr);
    s_fault_record.magic = PRV_FAULT_MAGIC;
    /* The record must be in SRAM before the reset request leaves the core. */
    __asm volatile("dsb" ::: "memory");
    SCB_AIRCR = SCB_AIRCR_VECTKEY | SCB_AIRCR_SYSRESETREQ;
    __asm volatile("dsb" ::: "memory");
    for (;;) {
    }
}

/* A fresh stack for the C part: the old SP may be at the very end of SRAM
 * (the stack guard, or the overflow fault itself). r0..r2 carry the
 * arguments through unchanged. */
__attribute__((naked, noreturn)) void g0_fault_stop(uint32_t kind __attribute__((unused)),
                                                    uint32_t pc __attribute__((unused)),
                                                    uint32_t lr __attribute__((unused)))
{
    __asm volatile("ldr  r3, =_estack         \n"
                   "mov  sp, r3               \n"
                   "ldr  r3, =prv_fault_stop_c\n"
                   "bx   r3                   \n"
                   ".ltorg                    \n");
}

/* The frame the core stacked is on MSP or PSP as EXC_RETURN bit 2 says (this
 * firmware only uses MSP; checked anyway). PC and LR are read out of it
 * before g0_fault_stop moves SP, which may land on top of the frame. The
 * exception number (IPSR) says which vector got us here: 3 for a real
 * HardFault, anything else for a vector nothing should raise. */
__attribute__((naked)) void HardFault_Handler(void)
{
    __asm volatile("movs r0, #4              \n"
                   "mov  r1, lr              \n"
                   "tst  r0, r1              \n"
                   "bne  1f                  \n"
                   "mrs  r0, msp             \n"
                   "b    2f                  \n"
                   "1:                       \n"
                   "mrs  r0, psp             \n"
                   "2:                       \n"
                   "ldr  r1, [r0, #24]       \n"
                   "ldr  r2, [r0, #20]       \n"
                   "mrs  r0, ipsr            \n"
                   "ldr  r3, =g0_fault_stop  \n"
                   "bx   r3                  \n"
                   ".ltorg                   \n");
}
