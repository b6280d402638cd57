#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Unit tests of the virtual G031's peripheral models against RM0444
behaviour (sim/g031/g031_periph.py), without a CPU."""
import unittest

import g031_deps  # noqa: E402
g031_deps.require()
import g031_periph as P  # noqa: E402


class FakeMachine:
    """The little a peripheral asks of the machine."""
    def __init__(self):
        self.flash = bytearray(b"\xff" * P.FLASH_SIZE)
        self.resets = []
        self.sensors = {}

    def pclk(self):
        return 64_000_000

    def flash_store(self, off, data):
        self.flash[off:off + len(data)] = data

    def request_reset(self, why):
        self.resets.append(why)


def unlocked_flash():
    m = FakeMachine()
    f = P.Flash(m)
    f.write(0x08, 0x45670123, 0)
    f.write(0x08, 0xCDEF89AB, 0)
    return m, f


class FlashTests(unittest.TestCase):
    def test_reset_locked_and_key_sequence_unlocks(self):  # RM0444 §3.3.6
        m, f = unlocked_flash()
        self.assertEqual(f.read(0x14, 0) >> 31, 0)
        self.assertEqual(P.Flash(FakeMachine()).read(0x14, 0) >> 31, 1)

    def test_wrong_key_locks_until_reset(self):  # §3.3.6
        f = P.Flash(FakeMachine())
        f.write(0x08, 0x12345678, 0)
        f.write(0x08, 0x45670123, 0)
        f.write(0x08, 0xCDEF89AB, 0)
        self.assertEqual(f.read(0x14, 0) >> 31, 1)
        f.reset()
        f.write(0x08, 0x45670123, 0)
        f.write(0x08, 0xCDEF89AB, 0)
        self.assertEqual(f.read(0x14, 0) >> 31, 0)

    def test_double_word_program_busy_then_eop(self):  # §3.3.8, DS12992 tPROG
        m, f = unlocked_flash()
        f.write(0x14, (1 << 24) | 1, 0)
        f.array_write(0x08000100, 4, 0x11223344, 0)
        f.array_write(0x08000104, 4, 0x55667788, 0)
        self.assertTrue(f.read(0x10, 1000) & (1 << 16))
        self.assertEqual(m.flash[0x100:0x108], b"\xff" * 8)
        sr = f.read(0x10, P.FLASH_PROG_NS)
        self.assertEqual(sr & ((1 << 16) | 1), 1)
        self.assertEqual(bytes(m.flash[0x100:0x108]), bytes.fromhex("4433221188776655"))

    def test_program_over_programmed_cell_is_progerr(self):  # §3.3.8
        m, f = unlocked_flash()
        m.flash[0x200] = 0
        f.write(0x14, 1, 0)
        f.array_write(0x08000200, 4, 0, 0)
        f.array_write(0x08000204, 4, 0, 0)
        self.assertTrue(f.read(0x10, 0) & (1 << 3))

    def test_second_word_elsewhere_is_pgaerr_and_byte_is_sizerr(self):  # §3.3.8
        m, f = unlocked_flash()
        f.write(0x14, 1, 0)
        f.array_write(0x08000300, 4, 0, 0)
        f.array_write(0x08000310, 4, 0, 0)
        self.assertTrue(f.read(0x10, 0) & (1 << 5))
        f.array_write(0x08000300, 1, 0, 0)
        self.assertTrue(f.read(0x10, 0) & (1 << 6))

    def test_write_without_pg_is_pgserr(self):  # §3.7.4 PGSERR
        m, f = unlocked_flash()
        f.array_write(0x08000300, 4, 0, 0)
        self.assertTrue(f.read(0x10, 0) & (1 << 7))
        self.assertEqual(m.flash[0x300], 0xFF)

    def test_page_erase_takes_erase_time_and_pnb_has_10_bits(self):  # §3.3.7, §3.7.5
        m, f = unlocked_flash()
        m.flash[31 * 2048:31 * 2048 + 4] = b"\0\0\0\0"
        f.write(0x14, (1 << 24) | 2 | (31 << 3) | (1 << 16), 0)
        self.assertTrue(f.read(0x10, P.FLASH_ERASE_NS - 1) & (1 << 16))
        self.assertEqual(f.read(0x10, P.FLASH_ERASE_NS) & 1, 1)
        self.assertEqual(bytes(m.flash[31 * 2048:31 * 2048 + 4]), b"\xff" * 4)


class RccTests(unittest.TestCase):
    def test_reset_value_has_hsi_on_and_ready(self):  # §5.4.1 (SVD corrected)
        r = P.Rcc(FakeMachine())
        self.assertEqual(r.read(0, 0) & 0x500, 0x500)

    def test_pll_ready_and_sws_follow(self):  # §5.4.1, §5.4.3
        r = P.Rcc(FakeMachine())
        r.write(0x0C, 2 | (8 << 8) | (1 << 28) | (1 << 29), 0)
        r.write(0, 0x500 | (1 << 24), 0)
        self.assertTrue(r.read(0, 0) & (1 << 25))
        r.write(0x08, 2, 0)
        self.assertEqual((r.read(0x08, 0) >> 3) & 7, 2)
        self.assertEqual(r.sysclk(), 64_000_000)

    def test_reset_flags_sticky_until_rmvf(self):  # §5.4 RCC_CSR
        r = P.Rcc(FakeMachine())
        r.set_reset_flags(1 << 29)
        r.reset()
        self.assertTrue(r.read(0x60, 0) & (1 << 29))
        r.write(0x60, 1 << 23, 0)
        self.assertEqual(r.read(0x60, 0) & 0xFE000000, 0)


class UsartTests(unittest.TestCase):
    def usart(self):
        u = P.Usart(FakeMachine())
        u.write(0x0C, 556, 0)            # 64 MHz / 556 = 115108 baud
        u.write(0x00, 1 | 4 | 8, 0)
        return u

    def test_tx_byte_takes_ten_bit_times_then_tc(self):  # §33.5.5
        u = self.usart()
        u.write(0x28, 0x55, 0)
        self.assertEqual(u.read(0x1C, 0) & (1 << 6), 0)
        end = 10 * 556 * P.NS / 64_000_000
        u.tick(end - 1)
        self.assertEqual(u.wire_out, [])
        u.tick(end)
        self.assertEqual(u.wire_out, [(0, 0x55)])
        self.assertTrue(u.read(0x1C, end) & (1 << 6))

    def test_second_byte_sets_ore_and_keeps_first(self):  # §33.5.6
        u = self.usart()
        u.receive_at(100, 0x11)
        u.receive_at(200, 0x22)
        u.tick(300)
        isr = u.read(0x1C, 300)
        self.assertTrue(isr & (1 << 3) and isr & (1 << 5))
        self.assertEqual(u.read(0x24, 300), 0x11)
        self.assertEqual(u.read(0x1C, 300) & (1 << 5), 0)

    def test_half_duplex_hears_own_byte_only_with_re(self):  # §33.5.14
        u = self.usart()
        u.write(0x08, 8, 0)
        u.write(0x28, 0xA5, 0)
        u.tick(10 ** 9)
        self.assertEqual(u.read(0x24, 0), 0xA5)
        u.write(0x00, 1 | 8, 0)
        u.write(0x28, 0x5A, 10 ** 9)
        u.tick(2 * 10 ** 9)
        self.assertEqual(u.read(0x1C, 0) & (1 << 5), 0)


class TimIwdgTests(unittest.TestCase):
    def test_psc_loaded_at_update_and_compare_sets_cc1if(self):  # §22.3.1, §22.3.7
        t = P.Tim2(FakeMachine())
        t.write(0x2C, 0xFFFFFFFF, 0)
        t.write(0x28, 63, 0)
        t.write(0x14, 1, 0)
        t.write(0x10, 0, 0)
        t.write(0x34, 1000, 0)
        t.write(0x00, 1, 0)
        self.assertEqual(t.read(0x24, 999_000), 999)
        t.tick(999_000)
        self.assertEqual(t.read(0x10, 0) & 2, 0)
        t.tick(1_000_000)
        self.assertTrue(t.read(0x10, 0) & 2)
        t.write(0x10, ~2, 0)                 # rc_w0
        self.assertEqual(t.read(0x10, 0) & 2, 0)

    def test_iwdg_resets_after_reload_period(self):  # §27.3
        m = FakeMachine()
        w = P.Iwdg(m)
        w.write(0, 0xCCCC, 0)
        w.write(0, 0x5555, 0)
        w.write(4, 4, 0)                      # /64
        w.write(8, 249, 0)                    # 250 * 64 / 32 kHz = 500 ms
        self.assertEqual(w.read(0x0C, 0), 3)  # PVU, RVU while updating
        w.write(0, 0xAAAA, 0)
        w.tick(499_999_999)
        self.assertEqual(m.resets, [])
        w.tick(500_000_000)
        self.assertEqual(m.resets, ["iwdg"])


# A bare-metal program (arm-none-eabi-as of the listing beside it) that does
# what boards/stm32g031/flash.c does for one double word (RM0444 §3.3.6,
# §3.3.8): unlock, CR = EOPIE | PG, the two words, r5 = FLASH_SR right after
# the second, wait while BSY1, r7 = FLASH_SR, lock, park.
PROGRAM_ONE_DOUBLE_WORD = bytes.fromhex(
    "0948"      # ldr  r0, =0x40022000      FLASH
    "0a49"      # ldr  r1, =0x45670123      KEY1
    "8160"      # str  r1, [r0, #8]         KEYR
    "0a49"      # ldr  r1, =0xCDEF89AB      KEY2
    "8160"      # str  r1, [r0, #8]
    "0a49"      # ldr  r1, =0x01000001      EOPIE | PG
    "4161"      # str  r1, [r0, #0x14]      CR
    "0a4a"      # ldr  r2, =0x08000800      the double word
    "0a4b"      # ldr  r3, =0x11223344
    "1360"      # str  r3, [r2]
    "0a4b"      # ldr  r3, =0x55667788
    "5360"      # str  r3, [r2, #4]         second word: starts the program
    "0569"      # ldr  r5, [r0, #0x10]      SR at once
    "0469"      # 1: ldr r4, [r0, #0x10]
    "640c"      # lsrs r4, r4, #17          BSY1 -> carry
    "fcd2"      # bcs  1b
    "0769"      # ldr  r7, [r0, #0x10]      SR after
    "0849"      # ldr  r1, =0x80000000      LOCK
    "4161"      # str  r1, [r0, #0x14]
    "fee7"      # b    .
    "00200240" "23016745" "ab89efcd" "01000001" "00080008" "44332211" "88776655" "00000080")


class MachineFlashTests(unittest.TestCase):
    """The machine hands CPU stores into the array to the FLASH model."""

    def test_second_word_sets_bsy1_before_the_next_instruction(self):  # §3.3.8
        import vg031
        from unicorn import arm_const as A
        image = bytearray(b"\xff" * 0x800)
        image[0:8] = (0x20002000).to_bytes(4, "little") + (0x08000101).to_bytes(4, "little")
        image[0x100:0x100 + len(PROGRAM_ONE_DOUBLE_WORD)] = PROGRAM_ONE_DOUBLE_WORD
        m = vg031.Machine(bytes(image))
        m.run_until(300_000)   # 300 us: tPROG is 85 us in the model
        sr_at_once, sr_after = m.uc.reg_read(A.UC_ARM_REG_R5), m.uc.reg_read(A.UC_ARM_REG_R7)
        self.assertTrue(sr_at_once & (1 << 16), "BSY1 not set after the second word: SR=%#x" % sr_at_once)
        self.assertEqual(sr_after & 0xC3FB, 1, "SR after: %#x (EOP alone expected)" % sr_after)
        self.assertEqual(bytes(m.flash[0x800:0x808]), bytes.fromhex("4433221188776655"))
        self.assertEqual(m.faults, [])


# Reset handler at 0x100: LDR r0, =0x20000001; LDR r1, [r0] (a word load from
# an odd address); b . -- HardFault handler at 0x200: b .
UNALIGNED_LOAD = bytes.fromhex("0148" "0168" "fee7" "00bf") + (0x20000001).to_bytes(4, "little")


class MachineFaultTests(unittest.TestCase):
    """Faults the M0+ raises that unicorn's M0 core does not."""

    def _machine(self, check):
        import vg031
        image = bytearray(b"\xff" * 0x800)
        image[0:16] = b"".join(v.to_bytes(4, "little") for v in (0x20002000, 0x08000101, 0, 0x08000201))
        image[0x100:0x100 + len(UNALIGNED_LOAD)] = UNALIGNED_LOAD
        image[0x200:0x202] = b"\xfe\xe7"
        m = vg031.Machine(bytes(image), check_alignment=check)
        m.run_until(20_000)
        return m

    def test_unaligned_word_load_is_a_hardfault(self):  # ARMv6-M A3.2.1, B1.5.6
        from unicorn import arm_const as A
        m = self._machine(True)
        self.assertEqual(len(m.faults), 1, m.faults)
        self.assertIn("unaligned 4-byte access at 0x20000001", m.faults[0][1])
        self.assertEqual(m.active, [3], "not in HardFault")
        self.assertEqual(m.pc & ~1, 0x08000200)
        sp = m.uc.reg_read(A.UC_ARM_REG_SP)
        stacked_pc = int.from_bytes(m.uc.mem_read(sp + 24, 4), "little")
        self.assertEqual(stacked_pc, 0x08000102, "the frame must return to the faulting LDR")

    def test_unchecked_machine_lets_it_pass(self):
        m = self._machine(False)
        self.assertEqual(m.faults, [])


# Reset handler at 0x100 pends PendSV (ICSR.PENDSVSET) and parks. PendSV at
# 0x200 pends SysTick (ICSR.PENDSTSET: the same priority 0, so it may not
# preempt, ARMv6-M B1.5.4), masks and unmasks (CPSID i, MSR PRIMASK), sets
# r5 = 1 and returns; SysTick at 0x300 then sets r6 = 1. Both handlers run
# from reset priorities, so the SysTick waits for PendSV's return.
SAME_PRIORITY_PENDS_IN_HANDLER = {
    0x100: bytes.fromhex("0148" "0249" "0160" "fee7" "04ed00e0" "00000010"),
    0x200: bytes.fromhex("0448" "0549" "0160" "72b6" "0022" "82f31088" "0125" "7047" "0000"
                         "04ed00e0" "00000004"),
    0x300: bytes.fromhex("0126" "7047"),
}


class MachineExceptionTests(unittest.TestCase):
    """Exception entry and return around PRIMASK (ARMv6-M B1.5)."""

    def test_unmask_with_same_priority_pending_runs_on(self):  # B1.5.3, B1.5.4
        import vg031
        from unicorn import arm_const as A
        image = bytearray(b"\xff" * 0x800)
        vectors = {0: 0x20002000, 1: 0x08000101, 14: 0x08000201, 15: 0x08000301}
        for n, v in vectors.items():
            image[4 * n:4 * n + 4] = v.to_bytes(4, "little")
        for at, code in SAME_PRIORITY_PENDS_IN_HANDLER.items():
            image[at:at + len(code)] = code
        m = vg031.Machine(bytes(image))
        m.run_until(200_000)   # 200 us: a few dozen instructions are needed
        self.assertEqual(m.uc.reg_read(A.UC_ARM_REG_R5), 1,
                         "PendSV stuck after MSR PRIMASK at pc %#x, active %s" % (m.pc, m.active))
        self.assertEqual(m.uc.reg_read(A.UC_ARM_REG_R6), 1, "SysTick not taken after PendSV returned")
        self.assertEqual(m.active, [])
        self.assertEqual(m.faults, [])


# Reset handler at 0x100 sets SCR.SLEEPONEXIT (r7 reads SCR back), starts
# SysTick every 1,600 core clocks (100 us at the reset HSI16) with its
# interrupt, then loops: r6 += 1; WFI. SysTick at 0x200: r5 += 1, and at
# the third one clears SLEEPONEXIT.
SLEEP_ON_EXIT = {
    0x100: bytes.fromhex("0548" "0221" "0160" "0768" "044a" "054b" "5360" "0723" "1360"
                         "0136" "30bf" "fce7" "10ed00e0" "10e000e0" "3f060000"),
    0x200: bytes.fromhex("0135" "032d" "02d1" "0248" "0021" "0160" "7047" "0000" "10ed00e0"),
}


class MachineSleepOnExitTests(unittest.TestCase):
    """SCR.SLEEPONEXIT (ARMv6-M B3.2.7): a return from Handler mode to
    Thread mode sleeps without running a Thread mode instruction."""

    def _run(self, us):
        import vg031
        from unicorn import arm_const as A
        image = bytearray(b"\xff" * 0x800)
        for n, v in {0: 0x20002000, 1: 0x08000101, 15: 0x08000201}.items():
            image[4 * n:4 * n + 4] = v.to_bytes(4, "little")
        for at, code in SLEEP_ON_EXIT.items():
            image[at:at + len(code)] = code
        m = vg031.Machine(bytes(image))
        m.run_until(us * 1000)
        self.assertEqual(m.faults, [])
        return m, [m.uc.reg_read(r) for r in (A.UC_ARM_REG_R5, A.UC_ARM_REG_R6, A.UC_ARM_REG_R7)]

    def test_scr_reads_back_what_was_written(self):  # B3.2.7
        _m, (_r5, _r6, scr) = self._run(50)
        self.assertEqual(scr, 2)

    def test_handler_return_sleeps_while_set(self):  # B3.2.7
        m, (ticks, passes, _scr) = self._run(250)
        self.assertEqual(ticks, 2)
        self.assertEqual(passes, 1, "Thread mode ran after a SysTick return with SLEEPONEXIT set")
        self.assertTrue(m.asleep)
        self.assertEqual(m.active, [])

    def test_cleared_in_the_handler_returns_to_thread(self):  # B3.2.7
        _m, (ticks, passes, _scr) = self._run(1050)
        self.assertEqual(ticks, 10)
        # ticks 1 and 2 slept on; 3 cleared the bit: each of 3..10 returned to the loop
        self.assertEqual(passes, 1 + 8)


class VclockTests(unittest.TestCase):
    """sim/g031/vclock.py: the master's clock on the bus's virtual time."""

    def test_stopped_bus_hands_the_clock_back_to_real_time(self):
        """A master that waits for the bus process to end (subprocess's
        wait sleeps on time.sleep) after the bus stopped: the clock goes on
        in real time from the last virtual time seen, it does not stall."""
        import os
        import tempfile
        import vclock
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "clock")
            bus_side = vclock.create(path)
            vclock.publish(bus_side, 5_000_000_000)
            clock = vclock.Clock(path)
            self.assertEqual(clock.ns(), 5_000_000_000)
            vclock.stop(bus_side)
            real = vclock.real_monotonic()
            clock.sleep(0.05)   # before the fix: waits STALL_S (60 s) and raises
            self.assertLess(vclock.real_monotonic() - real, 5.0)
            self.assertGreaterEqual(clock.ns(), 5_050_000_000)
            self.assertLess(clock.ns(), 5_000_000_000 + 60 * 10**9)


if __name__ == "__main__":
    unittest.main(verbosity=1)
