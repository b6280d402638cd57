/* SPDX-License-Identifier: Apache-2.0 */
/* Faults, reset cause and stack guard of the STM32G031 board. Fault path:
 * bridge free, .noinit record, SYSRESETREQ, with no hal calls and on a fresh
 * stack (a fault in here would lock the core up); why: README.md "Faults,
 * reset cause, stack". */
#include "fault.h"

#include "board_pins.h"
#include "g0_regs.h"
#include "g0_vectors.h"
#include "km_hal_system.h"
#include "reset_cause.h"

/* stm32g031.ld: the stack region at the bottom of SRAM, guard band lowest. */
extern uint32_t __stack_limit[], __stack_guard_end[], _estack[];

#define PRV_FAULT_MAGIC 0xFA017EC0u
#define PRV_ALIVE_MAGIC 0xA11FE5A5u
#define PRV_STACK_PAINT 0x5AFE57ACu
/* Left unpainted: the painting code's own frames at the top of the stack. */
#define PRV_PAINT_SKIP_WORDS 64u

/* Written just before SYSRESETREQ, read and cleared at the next boot (.noinit
 * survives a system reset); check = ~(magic ^ kind ^ pc ^ lr). */
typedef struct {
    uint32_t magic;
    uint32_t kind; /* IPSR number, or G0_FAULT_STACK_GUARD */
    uint32_t pc;   /* stacked PC (0 for the guard) */
    uint32_t lr;   /* stacked LR */
    uint32_t check;
} g0_fault_record_t;

static volatile g0_fault_record_t s_fault_record __attribute__((section(".noinit")));

/* Set at every boot; intact at the next only if SRAM survived (brown-out). */
static volatile uint32_t s_alive[2] __attribute__((section(".noinit")));

static km_reset_cause_t s_cause;

/* The previous run's fault record, for a debugger (magic 0: no fault). */
g0_fault_record_t g0_last_fault;

/* Fills the stack below the caller's frame with the paint pattern. */
void g0_stack_paint(void)
{
    uintptr_t end = (uintptr_t)_estack - 4u * PRV_PAINT_SKIP_WORDS;
    for (uint32_t *p = __stack_limit; (uintptr_t)p < end; p++) {
        *p = PRV_STACK_PAINT;
    }
}

/* Words of the guard band checked per call, in turn (the 32-word band
 * every 8 ms; docs/benchmarks.md "Control tick"). */
#define PRV_GUARD_SLICE_WORDS 4u
static uint32_t s_guard_next; /* word offset of the slice checked next */

/* Checks the next slice of the guard band; in RAM (SysTick, flash erases).
 * A load, an exclusive or and an or a word, one statement each (one
 * expression of volatile reads had GCC load every word first and spill). */
G0_RAMFUNC(g0_stack_guard_intact) bool g0_stack_guard_intact(void)
{
    const uint32_t at = s_guard_next;
    const uint32_t *const p = __stack_limit + at;
    _Static_assert(PRV_GUARD_SLICE_WORDS == 4u, "the slice is read as four words");
    uint32_t diff = p[0] ^ PRV_STACK_PAINT;
    diff |= p[1] ^ PRV_STACK_PAINT;
    diff |= p[2] ^ PRV_STACK_PAINT;
    diff |= p[3] ^ PRV_STACK_PAINT;
    const uint32_t next = at + PRV_GUARD_SLICE_WORDS;
    s_guard_next = __stack_limit + next < __stack_guard_end ? next : 0u;
    return diff == 0u;
}

/* Reads and clears RCC_CSR and the .noinit record; decodes the cause. */
void g0_reset_capture(void)
{
    uint32_t csr = RCC_CSR;
    RCC_CSR = csr | RCC_CSR_RMVF; /* keeps LSION; clears every reset flag */

    /* each word read once */
    const uint32_t magic = s_fault_record.magic, kind = s_fault_record.kind, pc = s_fault_record.pc;
    const uint32_t lr = s_fault_record.lr, check = s_fault_record.check;
    bool fault = magic == PRV_FAULT_MAGIC && check == ~(magic ^ kind ^ pc ^ lr);
    if (fault) {
        g0_last_fault = (g0_fault_record_t){magic, kind, pc, lr, check};
    }
    s_fault_record.magic = 0u;

    bool ram_kept = s_alive[0] == PRV_ALIVE_MAGIC && s_alive[1] == ~PRV_ALIVE_MAGIC;
    s_alive[0] = PRV_ALIVE_MAGIC;
    s_alive[1] = ~PRV_ALIVE_MAGIC;

    s_cause = g0_reset_cause_decode(csr, fault, ram_kept);
}

/* The cause captured at boot. */
km_reset_cause_t km_hal_reset_cause(void)
{
    return s_cause;
}

/* Bridge free (IN1 = IN2 = low, coast): pins from TIM3 to GPIO outputs, ODR
 * cleared before MODER switches so no pin goes high; port clock enabled in
 * case the fault came before km_hal_system_init(). */
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
    GPIO_BRR(PIN_DE_PORT) = 1u << PIN_DE_PIN;
#endif
}

/* Frees the bridge, writes the record, resets; reached from g0_fault_stop's asm. */
__attribute__((used, noreturn)) static void prv_fault_stop_c(uint32_t kind, uint32_t pc, uint32_t lr)
{
    prv_bridge_free();
    s_fault_record.kind = kind;
    s_fault_record.pc = pc;
    s_fault_record.lr = lr;
    s_fault_record.check = ~(PRV_FAULT_MAGIC ^ kind ^ pc ^ lr);
    s_fault_record.magic = PRV_FAULT_MAGIC;
    /* Record in SRAM before the reset request. */
    __asm volatile("dsb" ::: "memory");
    SCB_AIRCR = SCB_AIRCR_VECTKEY | SCB_AIRCR_SYSRESETREQ;
    __asm volatile("dsb" ::: "memory");
    for (;;) {
    }
}

/* Moves SP to the top of the stack, then prv_fault_stop_c (r0..r2 unchanged); in
 * RAM: the SysTick handler's call needs no veneer (docs/footprint.md "STM32G031F6"). */
G0_RAMFUNC(g0_fault_stop)
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

/* Reads stacked PC and LR (MSP or PSP per EXC_RETURN bit 2) before SP moves,
 * then g0_fault_stop(IPSR, pc, lr). */
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
