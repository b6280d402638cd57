#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""vg031: a virtual STM32G031 on unicorn (Debian's python3-unicorn) that
runs the shipped, unmodified images and answers on an emulated bus.

    vg031.py --boot km-boot-stm32g031.elf --app km-servo-app-stm32g031.kmfw
             [--until-main] [--tcp PORT] [--ms N]
    vg031.py --elf km-servo-stm32g031.elf ...

Unicorn gives the Cortex-M0 instruction set and memory; this file adds
what the core around it does: the NVIC, SCB and SysTick (ARMv6-M B3.2-B3.4),
exception entry with the stacked frame (B1.5.6) and its return (B1.5.8:
unicorn's core does not unstack), HardFault on an unmapped access,
system reset (AIRCR, IWDG) with flash kept. Virtual time advances one
instruction per core clock (CPI 1, an approximation: the M0+ takes 2-3
cycles for loads, branches and flash wait states); the CPU runs in
slices of 1 us and interrupts are taken between slices."""
import argparse
import ctypes
import socket
import sys


from unicorn import (Uc, UcError, UC_ARCH_ARM, UC_MODE_THUMB, UC_MODE_MCLASS, UC_PROT_ALL,  # noqa: E402
                     UC_HOOK_MEM_WRITE, UC_HOOK_MEM_READ, UC_HOOK_CODE, UC_HOOK_MEM_UNMAPPED, UC_HOOK_INTR)
from unicorn import arm_const as A  # noqa: E402

import g031_periph as P  # noqa: E402

RAM_BASE, RAM_SIZE = 0x20000000, 0x2000
UID = (0x00390041, 0x4E501120, 0x20383634)   # an arbitrary 96-bit unique ID (RM0444 §40.1)
# Fixed sensor inputs (ADC codes, 12 bits) until the plant is attached:
# pot mid-travel, zero current, 12 V supply through 100k/10k, NTC at 25 C.
DEFAULT_SENSORS = {0: 2048, 1: 2048, 2: 1365, 3: 2048}
QUIET_SLICE_NS = 16_000     # longest slice (vg031.Machine._slice_length)
RESET_PIN, RESET_PWR, RESET_SFT, RESET_IWDG = 1 << 26, 1 << 27, 1 << 28, 1 << 29
SCR_SLEEPONEXIT, SCR_SLEEPDEEP, SCR_SEVONPEND = 1 << 1, 1 << 2, 1 << 4   # ARMv6-M B3.2.7


class Scs:
    """NVIC, SCB and SysTick (ARMv6-M B3.2-B3.4; PM0223 §4): 2 priority bits
    per field (bits 7:6), word-access IPR, VTOR bits 31:7, AIRCR VECTKEY /
    SYSRESETREQ, ICSR PENDSV/PENDST, SCR's SLEEPONEXIT, SLEEPDEEP and
    SEVONPEND (B3.2.7: stored; SLEEPONEXIT acts at an exception return,
    Machine._exit), SysTick 24-bit down-counter on the core clock with
    COUNTFLAG cleared by a read."""

    def __init__(self, machine):
        self.m = machine
        self.reset()

    def reset(self):
        """Power-on / system reset values."""
        self.enabled = 0
        self.pending = 0          # bit n: IRQ n
        self.ipr = [0] * 8
        self.vtor = 0
        self.shpr2 = 0
        self.shpr3 = 0
        self.scr = 0              # SCR: bit 1 SLEEPONEXIT, 2 SLEEPDEEP, 4 SEVONPEND
        self.pend_sys = set()     # 11 SVC, 14 PendSV, 15 SysTick
        self.syst_csr = 0
        self.syst_rvr = 0
        self.syst_next = None
        self.countflag = False

    def prio(self, exc):
        """Priority of exception number exc (NMI -2, HardFault -1)."""
        if exc == 2:
            return -2
        if exc == 3:
            return -1
        if exc == 11:
            return self.shpr2 >> 24 & 0xC0
        if exc in (14, 15):
            return (self.shpr3 >> (16 if exc == 14 else 24)) & 0xC0
        irq = exc - 16
        return (self.ipr[irq >> 2] >> (8 * (irq & 3))) & 0xC0

    def _syst_period(self):
        return (self.syst_rvr + 1) * P.NS / self.m.hz

    def read(self, off, now):
        if off == 0x010:
            v = self.syst_csr | (1 << 16 if self.countflag else 0)
            self.countflag = False
            return v
        if off == 0x014:
            return self.syst_rvr
        if off == 0x018:
            if self.syst_next is None:
                return 0
            return int((self.syst_next - now) * self.m.hz / P.NS) % (self.syst_rvr + 1)
        if off in (0x100, 0x180):
            return self.enabled
        if off in (0x200, 0x280):
            return self.pending
        if 0x400 <= off < 0x420:
            return self.ipr[(off - 0x400) >> 2]
        if off == 0xD00:
            return 0x410CC601      # CPUID: Cortex-M0+ r0p1
        if off == 0xD04:
            active = self.m.active[-1] if self.m.active else 0
            return active | (1 << 28 if 14 in self.pend_sys else 0) | (1 << 26 if 15 in self.pend_sys else 0)
        if off == 0xD08:
            return self.vtor
        if off == 0xD0C:
            return 0xFA050000
        if off == 0xD10:
            return self.scr
        if off == 0xD14:
            return 0x208           # CCR: STKALIGN, UNALIGN_TRP (RES1 on ARMv6-M)
        if off == 0xD1C:
            return self.shpr2
        if off == 0xD20:
            return self.shpr3
        return 0

    def write(self, off, val, now):
        if off == 0x010:
            was = self.syst_csr & 1
            self.syst_csr = val & 7
            if val & 1 and not was:
                self.syst_next = now + self._syst_period()
            elif not val & 1:
                self.syst_next = None
        elif off == 0x014:
            self.syst_rvr = val & 0xFFFFFF
        elif off == 0x018:
            self.countflag = False
            if self.syst_csr & 1:
                self.syst_next = now + self._syst_period()
        elif off == 0x100:
            self.enabled |= val
        elif off == 0x180:
            self.enabled &= ~val
        elif off == 0x200:
            self.pending |= val
        elif off == 0x280:
            self.pending &= ~val
        elif 0x400 <= off < 0x420:
            self.ipr[(off - 0x400) >> 2] = val & 0xC0C0C0C0
        elif off == 0xD04:
            for bit, exc, on in ((28, 14, True), (27, 14, False), (26, 15, True), (25, 15, False)):
                if val & (1 << bit):
                    (self.pend_sys.add if on else self.pend_sys.discard)(exc)
        elif off == 0xD08:
            self.vtor = val & 0xFFFFFF80
        elif off == 0xD0C:
            if val >> 16 == 0x05FA and val & 4:
                self.m.request_reset("sysresetreq")
        elif off == 0xD10:
            self.scr = val & (SCR_SLEEPONEXIT | SCR_SLEEPDEEP | SCR_SEVONPEND)   # the rest is RAZ/WI
        elif off == 0xD1C:
            self.shpr2 = val & 0xC0000000
        elif off == 0xD20:
            self.shpr3 = val & 0xC0C00000

    def tick(self, now):
        """SysTick wraps: COUNTFLAG, and the exception with TICKINT."""
        while self.syst_next is not None and now >= self.syst_next:
            self.countflag = True
            if self.syst_csr & 2:
                self.pend_sys.add(15)
            self.syst_next += self._syst_period()

    def next_event(self, now):
        return self.syst_next


class Machine:
    """One STM32G031: core, memory and peripherals, in virtual time."""

    def __init__(self, flash_image, elves=(), watch=(), sensors=None, plant=None, check_alignment=False):
        self.flash_buf = (ctypes.c_ubyte * P.FLASH_SIZE).from_buffer_copy(flash_image.ljust(P.FLASH_SIZE, b"\xff"))
        self.flash = memoryview(self.flash_buf).cast("B")
        self.sensors = dict(DEFAULT_SENSORS if sensors is None else sensors)
        self.plant = plant          # g031_plant.Plant: ADC inputs from a moving shaft
        self.check_alignment = check_alignment  # unaligned accesses fault (_align_hook)
        self.now = 0
        self.instructions = 0
        self.resets = []            # [(time, reason)]
        self.faults = []            # [(time, kind, pc)]
        self.reset_request = None
        self.slice_ns = 1000        # interrupts are taken between slices
        self.horizon = None         # run_until's end: a WFI sleeps no further
        self.stall_ns = 0           # CPU time lost to flash stalls (_stall)
        self.wfi_sites = set()
        self.unmask_sites = set()   # the instruction after each CPSIE i / MSR PRIMASK
        self.watches = {addr: [] for addr in watch}   # address: [(time, instructions before the slice)]
        for path in elves:
            self.find_wfi(path)
        if not elves:
            self.scan_code(bytes(flash_image), P.FLASH_BASE)   # a bare program: its code is in the flash
        self.uc = None
        self.ram = bytearray(RAM_SIZE)
        self.rcc = P.Rcc(self)
        self.scs = Scs(self)
        self.blocks = []
        self._build_peripherals()
        self.rcc.set_reset_flags(RESET_PWR | RESET_PIN)
        self._power_on()

    def _build_peripherals(self):
        self.flashc = P.Flash(self)
        self.gpioa, self.gpiob = P.GpioA(self), P.GpioB(self)
        self.usart1 = P.Usart(self)
        self.tim2, self.tim3 = P.Tim2(self), P.Tim3(self)
        self.adc, self.dma, self.dmamux = P.Adc(self), P.Dma(self), P.Dmamux(self)
        self.iwdg = P.Iwdg(self)
        self.blocks = [self.rcc, self.flashc, self.gpioa, self.gpiob, self.usart1, self.tim2,
                       self.tim3, self.adc, self.dma, self.dmamux, self.iwdg]
        self.irq_blocks = (self.usart1, self.tim2, self.tim3, self.adc)
        self.timed_blocks = [self.flashc, self.usart1, self.tim2, self.tim3, self.adc, self.iwdg]
        self.by_page = {}
        for b in self.blocks:
            self.by_page.setdefault(b.base & ~0xFFF, []).append(b)
        self.unmodelled = set()
        # Reads that change state (RDR clears RXNE, RM0444 §33.8.10): the
        # slice after them is short. Other reads change nothing, and what
        # they show changes only at a peripheral event, which ends a slice.
        self.read_side_effects = {self.usart1.base + P.Usart.RDR}

    @property
    def hz(self):
        return self.rcc.sysclk()

    def pclk(self):
        return self.rcc.sysclk()

    # ---- memory -------------------------------------------------------------

    def _map(self):
        uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
        uc.ctl_set_cpu_model(A.UC_CPU_ARM_CORTEX_M0)
        addr = ctypes.addressof(self.flash_buf)
        uc.mem_map_ptr(P.FLASH_BASE, P.FLASH_SIZE, UC_PROT_ALL, addr)
        uc.mem_map_ptr(0x00000000, P.FLASH_SIZE, UC_PROT_ALL, addr)   # boot alias (RM0444 §2.5)
        uc.mem_map(RAM_BASE, RAM_SIZE)
        uc.mem_write(RAM_BASE, bytes(self.ram))
        uc.mem_map(0x1FFF7000, 0x1000)                                # engineering bytes: UID
        uc.mem_write(0x1FFF7590, b"".join(w.to_bytes(4, "little") for w in UID))
        for page in self.by_page:
            uc.mmio_map(page, 0x1000, self._mmio_read, page, self._mmio_write, page)
        uc.mmio_map(0xE000E000, 0x1000, self._scs_read, None, self._scs_write, None)
        uc.hook_add(UC_HOOK_MEM_WRITE, self._flash_hook, None, P.FLASH_BASE, P.FLASH_BASE + P.FLASH_SIZE - 1)
        uc.hook_add(UC_HOOK_MEM_WRITE, self._flash_hook, None, 0, P.FLASH_SIZE - 1)
        uc.hook_add(UC_HOOK_MEM_UNMAPPED, self._unmapped_hook)
        if self.check_alignment:
            for base, size in ((RAM_BASE, RAM_SIZE), (P.FLASH_BASE, P.FLASH_SIZE), (0, P.FLASH_SIZE)):
                uc.hook_add(UC_HOOK_MEM_READ | UC_HOOK_MEM_WRITE, self._align_hook, None, base, base + size - 1)
        uc.hook_add(UC_HOOK_INTR, self._intr_hook)
        for addr in self.watches:
            uc.hook_add(UC_HOOK_CODE, self._watch_hook, addr, addr, addr)
        for site in self.wfi_sites:
            uc.hook_add(UC_HOOK_CODE, self._wfi_hook, None, site, site)
        for site in self.unmask_sites:
            uc.hook_add(UC_HOOK_CODE, self._unmask_hook, None, site, site)
        self.uc = uc

    def find_wfi(self, elf_path):
        """WFI and unmask sites of an image's code sections."""
        from elftools.elf.elffile import ELFFile
        with open(elf_path, "rb") as f:
            for sec in ELFFile(f).iter_sections():
                if sec["sh_flags"] & 4 and sec["sh_type"] == "SHT_PROGBITS":
                    self.scan_code(sec.data(), sec["sh_addr"])

    def scan_code(self, data, base):
        """Records the WFI sites (unicorn's core just ends the run there)
        and the instruction after each CPSIE i / MSR PRIMASK in `data`
        at address `base`."""
        for i in range(0, len(data) - 1, 2):
            if data[i] == 0x30 and data[i + 1] == 0xBF:
                self.wfi_sites.add(base + i)
            elif data[i] == 0x62 and data[i + 1] == 0xB6:          # cpsie i
                self.unmask_sites.add(base + i + 2)
            elif (data[i + 1] == 0xF3 and data[i] & 0xF0 == 0x80 and i + 3 < len(data)
                  and data[i + 2] == 0x10 and data[i + 3] == 0x88):  # msr primask, rN
                self.unmask_sites.add(base + i + 4)

    def sample(self, channel, when):
        """The analog input of ADC channel `channel` at virtual time `when`:
        from the plant (driven by TIM3 CH1/CH2 on PA6/PA7 when those pins
        are in alternate function mode, RM0444 §7.3.2), else the fixed
        inputs of `sensors`."""
        if self.plant is None:
            return self.sensors.get(channel, 0)
        moder = self.gpioa.r[0x00]
        self.plant.drive_from(self.tim3, (moder >> 12) & 3 == 2 and (moder >> 14) & 3 == 2)
        self.plant.advance(when)
        return self.plant.code(channel)

    def mem_write(self, addr, data):
        """A bus master (DMA) writes memory."""
        self.uc.mem_write(addr, bytes(data))

    def flash_store(self, off, data):
        """The flash controller changes the array."""
        self.flash[off:off + len(data)] = data

    def _mmio_read(self, uc, off, size, page):
        addr = page + off
        if addr in self.read_side_effects:
            self.touched = True
        for b in self.by_page[page]:
            if b.base <= addr < b.base + 0x400:
                v = b.read(addr - b.base, self.now)
                return (v >> (8 * (addr & 3))) & ((1 << (8 * size)) - 1) if size < 4 else v
        self.unmodelled.add(addr)
        return 0

    def _mmio_write(self, uc, off, size, val, page):
        """A register write. Blocks with an interrupt line (and the SCS)
        may pend an interrupt at once: the slice after it is short; for the
        others only their next event can move (IWDG reload, a flash
        operation started)."""
        addr = page + off
        for b in self.by_page[page]:
            if b.base <= addr < b.base + 0x400:
                b.write(addr - b.base, val, self.now)
                if b in self.irq_blocks:
                    self.touched = True
                else:
                    nxt = b.next_event(self.now)
                    if nxt is not None:
                        self.due = min(self.due, nxt)
                return
        self.touched = True
        self.unmodelled.add(addr)

    def _scs_read(self, uc, off, size, _):
        if off == 0x010:
            self.touched = True   # COUNTFLAG clears on read
        return self.scs.read(off, self.now)

    def _scs_write(self, uc, off, size, val, _):
        self.touched = True
        self.scs.write(off, val, self.now)

    def _flash_hook(self, uc, access, addr, size, value, _):
        """A CPU store into the flash array reaches the controller at once:
        the second word of a double word starts the program (RM0444 §3.3.8),
        so the driver's very next FLASH_SR read must see BSY1, before it
        locks CR again. unicorn still writes the value into its RAM copy of
        the array; that store is undone at the next store or the end of the
        slice, so the controller always sees the array as it is."""
        self.touched = True
        self._undo_flash_writes()
        off = addr & (P.FLASH_SIZE - 1)
        self.flash_writes.append((off, bytes(self.flash[off:off + size])))
        self.flashc.array_write(P.FLASH_BASE + off, size, value, self.now)

    def _align_hook(self, uc, access, addr, size, value, _):
        """ARMv6-M A3.2.1: a halfword or word access that is not aligned to
        its size is a fault (UsageFault, escalated to HardFault on the M0+);
        unicorn's M0 core performs it, so the access is caught here and the
        slice stops at the instruction."""
        if addr & (size - 1):
            self.fault = ("unaligned %d-byte access at 0x%08x" % (size, addr), uc.reg_read(A.UC_ARM_REG_PC))
            uc.emu_stop()

    def _unmapped_hook(self, uc, access, addr, size, value, _):
        self.fault = ("unmapped", addr)
        return False

    def _intr_hook(self, uc, intno, _):
        self.fault = ("exception %d" % intno, uc.reg_read(A.UC_ARM_REG_PC))
        uc.emu_stop()

    def _watch_hook(self, uc, addr, size, watch):
        hits = self.watches[watch]
        if len(hits) < 1000:
            hits.append((self.now, self.instructions))

    def _wfi_hook(self, uc, addr, size, _):
        self.wfi_at = addr

    def _unmask_hook(self, uc, addr, size, _):
        """Right after PRIMASK may have been cleared: a pending interrupt
        that may preempt is taken before the next instruction (ARMv6-M
        B1.5.3), so the slice ends here and the next one starts in the
        handler (a lock right after an unlock would otherwise hide it until
        the next slice boundary). One that may not preempt (its priority not
        above the running handler's, B1.5.4) waits for the return: ending
        the slice for it would restart here and stop again, for ever
        (docs/virtual-g031.md "Found: servo 1 silent until its IWDG reset")."""
        if self._pending_exception() is not None:
            uc.emu_stop()

    # ---- reset and exceptions -------------------------------------------------

    def _power_on(self):
        self._map()
        self._core_reset()

    def request_reset(self, reason):
        """AIRCR.SYSRESETREQ, the IWDG or the NRST pin ("pin"): reset at
        the end of this slice."""
        if self.reset_request is None:
            self.reset_request = reason

    def _system_reset(self, reason):
        """System reset (RM0444 §5.1.2): peripherals and core to reset values,
        SRAM and flash keep their contents; RCC_CSR records the cause."""
        self.resets.append((self.now, reason))
        kind = {"iwdg": RESET_IWDG, "pin": 0}.get(reason, RESET_SFT)
        self.rcc.set_reset_flags(RESET_PIN | kind)
        for b in self.blocks:
            b.reset()
        self.scs.reset()
        self.ram = bytearray(self.uc.mem_read(RAM_BASE, RAM_SIZE))
        self.uc = None
        self._map()
        self._core_reset()

    def _core_reset(self):
        """Take SP and the reset vector from address 0 (the flash alias)."""
        sp = int.from_bytes(self.flash[0:4], "little")
        pc = int.from_bytes(self.flash[4:8], "little")
        self.uc.reg_write(A.UC_ARM_REG_MSP, sp)
        self.uc.reg_write(A.UC_ARM_REG_SP, sp)
        self.uc.reg_write(A.UC_ARM_REG_PRIMASK, 0)
        self.uc.reg_write(A.UC_ARM_REG_IPSR, 0)
        self.pc = pc & ~1
        self.active = []
        self.reset_request = None
        self.locked_up = False
        self.asleep = False
        self.touched = True
        self.due = 0

    def _pending_exception(self):
        """Highest-priority pending exception that may preempt, or None."""
        if not (self.scs.pending & self.scs.enabled or self.scs.pend_sys):
            return None
        primask = self.uc.reg_read(A.UC_ARM_REG_PRIMASK) & 1
        cur = min([self.scs.prio(e) for e in self.active], default=256)
        if primask:
            cur = min(cur, 0)
        best = None
        cands = [16 + i for i in range(32) if self.scs.pending & self.scs.enabled & (1 << i)]
        cands += sorted(self.scs.pend_sys)
        for exc in cands:
            p = self.scs.prio(exc)
            if p < cur and (best is None or p < self.scs.prio(best)):
                best = exc
        return best

    def _enter(self, exc, ret_pc):
        """Exception entry (ARMv6-M B1.5.6): push R0-R3, R12, LR, the return
        address and xPSR on the main stack (8-byte aligned, bit 9 of the
        stacked xPSR records the realignment), EXC_RETURN in LR, IPSR = exc,
        PC from the vector table at VTOR."""
        uc = self.uc
        sp = uc.reg_read(A.UC_ARM_REG_SP)
        xpsr = uc.reg_read(A.UC_ARM_REG_XPSR)
        align = 4 if sp & 4 else 0
        frame_sp = (sp - 32 - align) & 0xFFFFFFFF
        regs = [uc.reg_read(r) for r in (A.UC_ARM_REG_R0, A.UC_ARM_REG_R1, A.UC_ARM_REG_R2, A.UC_ARM_REG_R3,
                                         A.UC_ARM_REG_R12, A.UC_ARM_REG_LR)]
        stacked_psr = (xpsr & ~(1 << 9)) | (1 << 24) | ((1 << 9) if align else 0)
        frame = b"".join(v.to_bytes(4, "little") for v in regs + [ret_pc & ~1, stacked_psr])
        try:
            uc.mem_write(frame_sp, frame)
            vec = int.from_bytes(uc.mem_read(self.scs.vtor + 4 * exc, 4), "little")
        except UcError:
            self.locked_up = True
            self.faults.append((self.now, "lockup: stacking", ret_pc))
            return
        handler_mode = bool(self.active)
        uc.reg_write(A.UC_ARM_REG_SP, frame_sp)
        uc.reg_write(A.UC_ARM_REG_LR, 0xFFFFFFF1 if handler_mode else 0xFFFFFFF9)
        uc.reg_write(A.UC_ARM_REG_IPSR, exc)
        self.active.append(exc)
        if exc >= 16:
            self.scs.pending &= ~(1 << (exc - 16))
        self.scs.pend_sys.discard(exc)
        self.pc = vec & ~1

    def _exit(self, exc_return):
        """Exception return (ARMv6-M B1.5.8): a branch to EXC_RETURN in Handler
        mode pops the frame the entry pushed and goes back to the previous
        mode. unicorn's core does not do it (it faults at 0xFFFFFFF8).
        True when the core then sleeps: a return from Handler mode to
        Thread mode with SCR.SLEEPONEXIT set enters the sleep a WFI would
        (B3.2.7, B1.5.19 "sleep-on-exit"), whatever PRIMASK holds; no
        Thread mode instruction runs, and the next exception is taken with
        the Thread mode state as it returned."""
        uc = self.uc
        sp = uc.reg_read(A.UC_ARM_REG_SP)
        words = [int.from_bytes(uc.mem_read(sp + 4 * i, 4), "little") for i in range(8)]
        for reg, val in zip((A.UC_ARM_REG_R0, A.UC_ARM_REG_R1, A.UC_ARM_REG_R2, A.UC_ARM_REG_R3,
                             A.UC_ARM_REG_R12, A.UC_ARM_REG_LR), words):
            uc.reg_write(reg, val)
        psr = words[7]
        self.active.pop()
        if exc_return & 0xF == 0xD:
            self.faults.append((self.now, "return to PSP not modelled", words[6]))
        uc.reg_write(A.UC_ARM_REG_SP, (sp + 32 + (4 if psr & (1 << 9) else 0)) & 0xFFFFFFFF)
        uc.reg_write(A.UC_ARM_REG_APSR, psr & 0xF0000000)
        uc.reg_write(A.UC_ARM_REG_IPSR, self.active[-1] if self.active else 0)
        self.pc = words[6] & ~1
        return not self.active and bool(self.scs.scr & SCR_SLEEPONEXIT)

    def _sync_active(self):
        """Exception returns happened inside unicorn: drop finished ones."""
        if not self.active:
            return
        ipsr = self.uc.reg_read(A.UC_ARM_REG_IPSR) & 0x3F
        while self.active and self.active[-1] != ipsr:
            self.active.pop()

    def _fault(self, kind, pc):
        """HardFault (or lockup inside NMI/HardFault: the core stops, B1.5.15)."""
        self.faults.append((self.now, kind, pc))
        if any(e in (2, 3) for e in self.active):
            self.locked_up = True
            return
        self._enter(3, pc)

    # ---- running -------------------------------------------------------------

    def _levels(self):
        """Peripheral interrupt lines into the NVIC pending bits (level
        sensitive: an active interrupt does not pend again until it returns)."""
        for irq, block in ((15, self.tim2), (16, self.tim3), (27, self.usart1), (12, self.adc)):
            if block.irq() and (16 + irq) not in self.active:
                self.scs.pending |= 1 << irq

    def _tick_all(self):
        """Every block with time-driven state to `now`."""
        for b in self.timed_blocks:
            b.tick(self.now)
        self.scs.tick(self.now)

    def _next_event(self):
        times = [b.next_event(self.now) for b in self.blocks] + [self.scs.next_event(self.now)]
        times = [t for t in times if t is not None and t > self.now]
        return min(times) if times else self.now + P.NS // 1000

    def _undo_flash_writes(self):
        """Flash is RAM to unicorn: undo the CPU's stores into the array (the
        controller took each one when it was made, see _flash_hook)."""
        writes, self.flash_writes = self.flash_writes, []
        for off, old in reversed(writes):
            self.flash[off:off + len(old)] = old

    def _run_slice(self, ns):
        """Runs the CPU for `ns` of virtual time (or to a WFI, an exception
        return or a fault); true when the core sleeps after it (a WFI, or
        sleep-on-exit)."""
        count = max(1, int(self.hz * ns // P.NS))
        self.flash_writes, self.fault, self.wfi_at = [], None, None
        err = None
        try:
            self.uc.emu_start(self.pc | 1, 0xFFFFFFFF, 0, count)
        except UcError as e:
            err = e
        self.pc = self.uc.reg_read(A.UC_ARM_REG_PC)
        self.instructions += count
        self.now += ns
        self._undo_flash_writes()
        if (self.pc & 0xFFFFFFF0) == 0xFFFFFFF0 and self.active:
            return self._exit(self.pc | 1)
        if self.fault or err:
            kind = self.fault[0] if self.fault else str(err)
            if kind.startswith("unaligned"):
                self.pc = self.fault[1]   # a synchronous fault returns to the faulting instruction (B1.5.6)
            self._fault(kind, self.pc)
            return False
        return self.wfi_at is not None and self.pc == self.wfi_at + 2

    def hang(self, addr=0x0800E7F0):
        """Fault injection for tests: the CPU parks in `b .` at addr (an
        erased cell below the store) with interrupts masked, as a main
        loop stuck for ever would; only the IWDG gets it out."""
        self.flash[addr - P.FLASH_BASE:addr - P.FLASH_BASE + 2] = b"\xfe\xe7"
        self.uc.reg_write(A.UC_ARM_REG_PRIMASK, 1)
        self.pc = addr

    def bad_load(self, addr=0x0800E7F0):
        """Fault injection for tests: the CPU goes on at addr (an erased
        cell below the store) with a word load through a stray pointer
        (0x30000000, unmapped), a HardFault (ARMv6-M B1.5.6); returns the
        address of the faulting load."""
        off = addr - P.FLASH_BASE
        self.flash[off:off + 8] = bytes.fromhex("0048" "0068") + (0x30000000).to_bytes(4, "little")
        self.pc = addr
        return addr + 2

    def _slice_length(self):
        """A slice of slice_ns; after a slice that touched no peripheral,
        with no interrupt pending, up to QUIET_SLICE_NS or the next
        peripheral event: nothing can pend an interrupt before it."""
        if self.touched or self.scs.pending & self.scs.enabled or self.scs.pend_sys:
            return self.slice_ns
        room = min(self.due, self.horizon if self.horizon is not None else self.due) - self.now
        return max(self.slice_ns, min(QUIET_SLICE_NS, int(room)))

    def _fetches_flash(self):
        """The CPU's next access is an instruction or vector fetch from the
        flash array (the boot alias at 0 included)."""
        if self._pending_exception() is not None:
            return self.scs.vtor < RAM_BASE
        return self.pc < P.FLASH_BASE + P.FLASH_SIZE and (self.pc >= P.FLASH_BASE or self.pc < P.FLASH_SIZE)

    def _stall(self):
        """A flash fetch while BSY1: the CPU waits for the end of the
        program or erase (RM0444 §3.3.7, §3.3.8: a flash read during an
        operation stalls the bus until it completes); the peripherals run
        on, interrupts wait (their handlers and vectors are in flash)."""
        end = self.flashc.busy_until
        if self.horizon is not None:
            end = min(end, self.horizon)
        start = self.now
        while self.now < end and not self.reset_request:
            self.now = max(self.now, min(self.due, end))
            self._tick_all()
            self._levels()
            self.due = self._next_event()
        self.stall_ns += self.now - start
        if self.reset_request:
            self._system_reset(self.reset_request)

    def step(self, ns=None):
        """One slice: CPU, peripherals, interrupts, resets."""
        if self.asleep:
            self._sleep()
            return
        if self.now < self.flashc.busy_until and self._fetches_flash():
            self._stall()
            return
        ns = self._slice_length() if ns is None else ns
        self.touched = False
        self._sync_active()
        exc = self._pending_exception()
        if exc is not None:
            self._enter(exc, self.pc)
        if self.locked_up:
            sleep = True
            self.now += ns
        else:
            sleep = self._run_slice(ns)
        self._sync_active()
        if self.touched or sleep or self.now >= self.due:
            self._tick_all()
            self._levels()
            self.due = self._next_event()
        if self.reset_request:
            self._system_reset(self.reset_request)
            return
        if sleep:
            self.asleep = True
            self.due = self._next_event()
            self._sleep()

    def _sleep(self):
        """WFI or sleep-on-exit: time passes to the next event until an interrupt is pending
        (PRIMASK does not stop the wake-up, B1.5.19), or up to the horizon
        of run_until (the core stays asleep: the next step goes on)."""
        while True:
            if self.scs.pending & self.scs.enabled or self.scs.pend_sys or self.reset_request:
                self.asleep = False
                return
            if self.horizon is not None and self.due > self.horizon:
                self.now = max(self.now, self.horizon)
                return
            self.now = max(self.now, self.due)
            self._tick_all()
            self._levels()
            self.due = self._next_event()
            if self.reset_request:
                self._system_reset(self.reset_request)
                return

    def run_until(self, t_ns, stop=None):
        """Runs until virtual time t_ns, or until stop() is true."""
        self.horizon = t_ns
        while self.now < t_ns:
            self.step()
            if stop is not None and stop():
                return True
        return False

    # ---- the bus ---------------------------------------------------------------

    def bit_ns(self, baud):
        return P.NS / baud

    def send(self, data, baud, start=None):
        """Puts bytes on the wire back to back from `start` (default: now).
        Returns the end of the last stop bit."""
        t = self.now if start is None else start
        bit = self.bit_ns(baud)
        for byte in data:
            self.wire_in(t + 9.5 * bit, byte)
            t += 10 * bit
        return t

    def wire_in(self, when, byte, framing_error=False):
        """A byte from the wire completes in USART1's receiver at `when`
        (the middle of its stop bit); the next event may now be sooner."""
        self.usart1.receive_at(when, byte, framing_error)
        self.due = min(self.due, when)

    def take_output(self):
        """Bytes the MCU put on the wire since the last call: [(start, byte)]."""
        out, self.usart1.wire_out = self.usart1.wire_out, []
        return out


def flash_from_images(boot=None, app_kmfw=None, elf=None):
    """The 64 KiB flash contents from the images (ELF load segments; the
    update image at the address its header names: the application region,
    0x08002000 on the 64 KiB layout, 0x08001000 on the 32 KiB one)."""
    from elftools.elf.elffile import ELFFile
    flash = bytearray(b"\xff" * P.FLASH_SIZE)
    for path in [p for p in (boot, elf) if p]:
        with open(path, "rb") as f:
            for seg in ELFFile(f).iter_segments():
                if seg["p_type"] != "PT_LOAD" or not seg["p_filesz"]:
                    continue
                addr = seg["p_paddr"] - P.FLASH_BASE
                if 0 <= addr < P.FLASH_SIZE:
                    flash[addr:addr + seg["p_filesz"]] = seg.data()
    if app_kmfw:
        with open(app_kmfw, "rb") as f:
            img = f.read()
        at = int.from_bytes(img[20:24], "little") - P.FLASH_BASE  # header word 5: base
        flash[at:at + len(img)] = img
    return bytes(flash)


def symbol(elf_path, name):
    """Address of a symbol of an ELF."""
    from elftools.elf.elffile import ELFFile
    with open(elf_path, "rb") as f:
        for s in ELFFile(f).get_section_by_name(".symtab").iter_symbols():
            if s.name == name:
                return s["st_value"] & ~1
    raise KeyError(name)


def make(args, watch=(), check_alignment=False):
    """A machine from command-line style arguments."""
    elves = [p for p in (args.boot, args.elf, args.app_elf) if p]
    return Machine(flash_from_images(args.boot, args.app, args.elf), elves=elves, watch=watch,
                   check_alignment=check_alignment or getattr(args, "check_alignment", False))


def serve_tcp(m, port, baud):
    """Byte port: what a client sends goes on the wire at the current
    virtual time with the bit timing of `baud`; what the MCU sends comes back."""
    srv = socket.socket()
    srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    srv.bind(("127.0.0.1", port))
    srv.listen(1)
    conn, _ = srv.accept()
    conn.setblocking(False)
    wire_free = 0
    while True:
        try:
            data = conn.recv(4096)
            if data == b"":
                return
            wire_free = m.send(data, baud, max(m.now, wire_free))
        except BlockingIOError:
            pass
        m.run_until(m.now + 100_000)
        out = m.take_output()
        if out:
            conn.sendall(bytes(b for _t, b in out))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--boot")
    ap.add_argument("--app", help="update image (.kmfw) for the application region")
    ap.add_argument("--app-elf", help="the application's ELF (its symbols and WFI sites)")
    ap.add_argument("--elf", help="a stand-alone image linked at 0x08000000")
    ap.add_argument("--ms", type=float, default=10.0)
    ap.add_argument("--tcp", type=int)
    ap.add_argument("--baud", type=int, default=1000000)
    ap.add_argument("--check-alignment", action="store_true",
                    help="unaligned halfword/word accesses fault, as on the M0+ (about 5x slower)")
    a = ap.parse_args()
    m = make(a)
    if a.tcp:
        serve_tcp(m, a.tcp, a.baud)
        return 0
    import time
    real = time.perf_counter()
    m.run_until(int(a.ms * 1e6))
    real = time.perf_counter() - real
    print("t=%.3f ms instructions=%d pc=0x%08x resets=%s faults=%s unmodelled=%s" % (
        m.now / 1e6, m.instructions, m.pc, m.resets, m.faults, sorted(hex(x) for x in m.unmodelled)))
    print("speed: %.0f virtual us per real second (%.3f s real)" % (m.now / 1e3 / real, real))
    return 0


if __name__ == "__main__":
    sys.exit(main())
