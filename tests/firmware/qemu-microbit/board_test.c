/* SPDX-License-Identifier: Apache-2.0 */
/* Board driver test for qemu-microbit, run in QEMU with semihosting: NVMC
 * erase/program/read rules, persistence of NVMC-programmed flash across a
 * guest reset (SYSRESETREQ), the 1 MHz tick, the one-shot timer, the
 * interrupt lock, UART baud checks, motor/sensor hook-up, entropy. Prints each
 * check; exits with the number of failures (0 = all pass).
 *
 * Two boots: a marker in .noinit RAM (neither loaded nor zeroed, and QEMU
 * keeps RAM across a system reset) says which phase we are in. */
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "km_board.h"
#include "km_hal_motor.h"
#include "km_hal_sensors.h"
#include "km_hal_system.h"
#include "km_hal_time.h"
#include "km_hal_uart.h"
#include "semihost.h"

#define PRV_MAGIC 0x4B4D5154u /* "KMQT" */
#define PRV_FLASH_MARKER 0xC0FFEE01u
#define PRV_TIMER_SLACK_US 50000u /* QEMU's clock follows the host's: allow scheduling jitter */

typedef struct {
    uint32_t magic;
    uint32_t phase;
    uint32_t failures;
    uint32_t checks;
} prv_noinit_t;

static prv_noinit_t s_boot __attribute__((section(".noinit")));

static volatile uint32_t s_fired_count;
static volatile uint32_t s_fired_tick;

static void prv_check(bool ok, const char *what)
{
    s_boot.checks++;
    km_semihost_write0(ok ? "PASS " : "FAIL ");
    km_semihost_write0(what);
    km_semihost_write0("\n");
    if (!ok) {
        s_boot.failures++;
    }
}

static void prv_info(const char *what, uint32_t value)
{
    km_semihost_write0("INFO ");
    km_semihost_write0(what);
    km_semihost_write0(" = ");
    km_semihost_write_hex(value);
    km_semihost_write0("\n");
}

static void prv_on_timer(void *ctx)
{
    (void)ctx;
    s_fired_tick = km_hal_time_now();
    s_fired_count++;
}

static void prv_wait_us(uint32_t us)
{
    uint32_t start = km_hal_time_now();
    while (km_hal_time_now() - start < us) {
    }
}

static bool prv_page_is(const km_flash_t *f, uint32_t page, uint32_t word)
{
    for (uint32_t off = 0; off < f->page_size; off += 4u) {
        uint32_t v = 0;
        if (f->read(f->ctx, page * f->page_size + off, &v, 4u) != KM_FLASH_OK || v != word) {
            return false;
        }
    }
    return true;
}

static void prv_test_flash(const km_flash_t *f)
{
    prv_check(f->page_size == 1024u && f->prog_size == 4u && f->page_count >= 2u,
              "flash geometry: 1 KiB pages, 4-byte cells, >= 2 pages");
    uint32_t first = 0;
    (void)f->read(f->ctx, 0u, &first, 4u);
    prv_info("store word 0 before any erase (QEMU: 0x00 outside the image)", first);

    prv_check(f->erase(f->ctx, 0u) == KM_FLASH_OK, "erase page 0");
    prv_check(prv_page_is(f, 0u, 0xFFFFFFFFu), "erased page 0 reads all 0xFF");

    const uint32_t data[2] = {0x12345678u, 0xA5A5005Au};
    uint32_t back[2] = {0, 0};
    prv_check(f->program(f->ctx, 8u, data, sizeof data) == KM_FLASH_OK, "program 2 cells at offset 8");
    prv_check(f->read(f->ctx, 8u, back, sizeof back) == KM_FLASH_OK && memcmp(back, data, sizeof data) == 0,
              "read back the programmed cells");

    const uint32_t again = 0x00000000u;
    prv_check(f->program(f->ctx, 12u, &again, 4u) == KM_FLASH_ERR_PROGRAM,
              "program onto a programmed cell is refused");
    (void)f->read(f->ctx, 12u, back, 4u);
    prv_check(back[0] == data[1], "refused program leaves the cell untouched");

    uint8_t unaligned_src[9] = {0, 1, 2, 3, 4, 5, 6, 7, 8};
    prv_check(f->program(f->ctx, 16u, &unaligned_src[1], 8u) == KM_FLASH_OK,
              "program from an unaligned source buffer");
    uint8_t bytes[8];
    prv_check(f->read(f->ctx, 16u, bytes, 8u) == KM_FLASH_OK && memcmp(bytes, &unaligned_src[1], 8u) == 0,
              "read back bytes from the unaligned program");

    prv_check(f->program(f->ctx, 2u, data, 4u) == KM_FLASH_ERR_ALIGN, "misaligned offset refused");
    prv_check(f->program(f->ctx, 24u, data, 3u) == KM_FLASH_ERR_ALIGN, "partial cell refused");
    uint32_t end = f->page_count * f->page_size;
    prv_check(f->program(f->ctx, end, data, 4u) == KM_FLASH_ERR_ALIGN, "program past the region refused");
    prv_check(f->read(f->ctx, end - 4u, back, 8u) == KM_FLASH_ERR_ALIGN, "read past the region refused");
    prv_check(f->erase(f->ctx, f->page_count) == KM_FLASH_ERR_ALIGN, "erase past the region refused");

    prv_check(f->erase(f->ctx, 0u) == KM_FLASH_OK && prv_page_is(f, 0u, 0xFFFFFFFFu),
              "re-erase page 0 after programming");
    uint32_t last = f->page_count - 1u;
    prv_check(f->erase(f->ctx, last) == KM_FLASH_OK && prv_page_is(f, last, 0xFFFFFFFFu), "erase last page");
}

static void prv_test_time(void)
{
    prv_check(km_hal_time_tick_hz() == 1000000u, "tick is 1 MHz");
    uint32_t t0 = km_hal_time_now();
    prv_wait_us(1000u);
    uint32_t t1 = km_hal_time_now();
    prv_check(t1 - t0 >= 1000u && t1 - t0 < 1000u + PRV_TIMER_SLACK_US, "tick advances (1 ms busy wait)");
    prv_info("tick after 1 ms wait, delta", t1 - t0);

    s_fired_count = 0u;
    uint32_t at = km_hal_time_now() + 2000u;
    km_hal_timer_at(at, prv_on_timer, NULL);
    prv_check(s_fired_count == 0u, "one-shot not fired before its time");
    while (s_fired_count == 0u && (int32_t)(km_hal_time_now() - at) < (int32_t)PRV_TIMER_SLACK_US) {
        km_hal_idle();
    }
    prv_check(s_fired_count == 1u, "one-shot fired");
    prv_check((int32_t)(s_fired_tick - at) >= 0 && s_fired_tick - at < PRV_TIMER_SLACK_US,
              "one-shot fired at or after its tick");
    prv_info("one-shot lateness us", s_fired_tick - at);
    prv_wait_us(3000u);
    prv_check(s_fired_count == 1u, "one-shot fires once");

    s_fired_count = 0u;
    km_hal_timer_at(km_hal_time_now() - 10u, prv_on_timer, NULL);
    prv_check(s_fired_count == 1u, "one-shot in the past fires at once");

    s_fired_count = 0u;
    km_hal_timer_at(km_hal_time_now() + 1000u, prv_on_timer, NULL);
    km_hal_timer_cancel();
    prv_wait_us(3000u);
    prv_check(s_fired_count == 0u, "cancelled one-shot does not fire");

    s_fired_count = 0u;
    km_hal_timer_at(km_hal_time_now() + 100000u, prv_on_timer, NULL);
    at = km_hal_time_now() + 1000u;
    km_hal_timer_at(at, prv_on_timer, NULL);
    prv_wait_us(5000u);
    prv_check(s_fired_count == 1u && s_fired_tick - at < PRV_TIMER_SLACK_US,
              "re-arming replaces the pending shot");

    s_fired_count = 0u;
    uint32_t irq = km_hal_irq_lock();
    km_hal_timer_at(km_hal_time_now(), prv_on_timer, NULL);
    prv_wait_us(500u);
    bool held = s_fired_count == 0u;
    km_hal_irq_restore(irq);
    prv_check(held && s_fired_count == 1u, "irq lock holds the timer interrupt until restore");
}

static void prv_rx(void *ctx, uint8_t byte, uint32_t tick, bool lost)
{
    (void)ctx;
    (void)byte;
    (void)tick;
    (void)lost;
}

static void prv_test_misc(void)
{
    prv_check(!km_hal_uart_init(300u, prv_rx, NULL), "uart refuses 300 baud");
    prv_check(km_hal_uart_init(1000000u, prv_rx, NULL), "uart accepts 1 Mbaud");
    prv_check(km_hal_uart_init(115200u, prv_rx, NULL), "uart accepts 115200 baud");
    static const uint8_t s_hello[] = "km\r\n";
    prv_check(km_hal_uart_send(s_hello, 4u), "uart send starts");
    uint32_t t0 = km_hal_time_now();
    while (km_hal_uart_tx_busy() && km_hal_time_now() - t0 < PRV_TIMER_SLACK_US) {
    }
    prv_check(!km_hal_uart_tx_busy(), "uart send completes");

    km_hal_motor_init();
    km_board_motor_cmd_t cmd = km_board_motor_command();
    prv_check(cmd.mode == KM_BOARD_MOTOR_FREE, "motor starts free");
    km_hal_motor_drive(1500);
    cmd = km_board_motor_command();
    prv_check(cmd.mode == KM_BOARD_MOTOR_DRIVE && cmd.pwm == 1000, "motor drive clamps to 1000");
    km_hal_motor_brake();
    prv_check(km_board_motor_command().mode == KM_BOARD_MOTOR_BRAKE, "motor brake recorded");

    km_hal_sensors_init();
    km_sensors_t s;
    km_hal_sensors_read(&s);
    prv_check(s.voltage_mv == 0 && s.position == 0, "sensors read zero until a plant publishes");
    km_sensors_t pub = {
        .position = 1234, .current_ma = -50, .voltage_mv = 12000, .temperature_c10 = 251, .faults = 0};
    km_board_sensors_publish(&pub);
    km_hal_sensors_read(&s);
    /* Member by member: memcmp would also compare the padding after faults. */
    prv_check(s.position == pub.position && s.current_ma == pub.current_ma &&
                  s.voltage_mv == pub.voltage_mv && s.temperature_c10 == pub.temperature_c10 &&
                  s.faults == pub.faults,
              "sensors return the published readings");

    uint32_t e1 = km_hal_entropy();
    uint32_t e2 = km_hal_entropy();
    prv_info("entropy 1", e1);
    prv_info("entropy 2", e2);
    prv_check(e1 != e2, "entropy differs between calls (RNG modelled)");
}

static void prv_phase_before_reset(const km_flash_t *f)
{
    prv_test_flash(f);
    prv_test_time();
    prv_test_misc();

    const uint32_t marker = PRV_FLASH_MARKER;
    prv_check(f->erase(f->ctx, 1u) == KM_FLASH_OK &&
                  f->program(f->ctx, f->page_size, &marker, 4u) == KM_FLASH_OK,
              "write a persistence marker in store page 1");
    km_semihost_write0("INFO resetting via SYSRESETREQ\n");
    s_boot.phase = 2u;
    km_hal_system_reset();
}

static void prv_phase_after_reset(const km_flash_t *f)
{
    km_semihost_write0("INFO booted again after SYSRESETREQ\n");
    uint32_t v = 0;
    (void)f->read(f->ctx, f->page_size, &v, 4u);
    prv_check(v == PRV_FLASH_MARKER, "NVMC-programmed flash survives a guest reset");
    prv_check(prv_page_is(f, f->page_count - 1u, 0xFFFFFFFFu), "erased page stays erased across reset");
    prv_check(km_hal_time_now() < 1000000u, "TIMER0 restarted from 0 at reset");
}

int main(void)
{
    km_hal_system_init();
    km_hal_time_init();
    const km_flash_t *f = km_board_flash();

    if (s_boot.magic != PRV_MAGIC) {
        s_boot = (prv_noinit_t){.magic = PRV_MAGIC, .phase = 1u};
        km_semihost_write0("km-board-test-qemu-microbit: phase 1\n");
        prv_phase_before_reset(f);
    }
    prv_phase_after_reset(f);

    uint32_t failures = s_boot.failures;
    km_semihost_write_u32(s_boot.checks);
    km_semihost_write0(" checks, ");
    km_semihost_write_u32(failures);
    km_semihost_write0(" failed\n");
    s_boot.magic = 0u; /* a later run in the same QEMU starts over */
    km_semihost_exit(failures == 0u ? 0 : (int)(failures > 100u ? 100u : failures));
}
