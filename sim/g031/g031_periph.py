# SPDX-License-Identifier: Apache-2.0
"""Peripheral models of the virtual STM32G031, one class per block, each
after its RM0444 section. Pure Python, no unicorn: the unit tests drive
them directly (tests/g031/test_g031_periph.py). Time is virtual, in
nanoseconds, handed in by the machine (vg031.py) as `now`."""
import bisect

import g031_regmap as regmap
from g031_errata import reset_value

NS = 1_000_000_000
LSI_HZ = 32_000          # DS12992 "LSI oscillator characteristics": 32 kHz typical
HSI_HZ = 16_000_000
# DS12992 table "Flash memory characteristics", typical values.
FLASH_PROG_NS = 85_000       # 64-bit programming time
FLASH_ERASE_NS = 22_000_000  # page erase time (max 40 ms)
FLASH_BASE = 0x08000000
FLASH_SIZE = 0x10000
FLASH_PAGE = 2048


class Block:
    """A register block: storage initialised from the SVD reset values
    (with the errata applied); subclasses give registers behaviour."""
    name = ""

    def __init__(self, machine):
        self.m = machine
        self.base = regmap.PERIPHERALS[self.name][0]
        self.reset()

    def reset(self):
        """All registers to their reset values."""
        regs = regmap.PERIPHERALS[self.name][1]
        self.r = {off: reset_value(regmap, self.name, rn) for rn, (off, _s, _v, _f) in regs.items()}

    def off(self, reg):
        """Offset of a named register."""
        return regmap.PERIPHERALS[self.name][1][reg][0]

    def read(self, off, now):
        """Register read; unknown offsets read as stored (0)."""
        return self.r.get(off, 0)

    def write(self, off, val, now):
        """Register write: plain storage unless a subclass says otherwise."""
        self.r[off] = val & 0xFFFFFFFF

    def tick(self, now):
        """Advance to `now` (called after every slice of CPU time)."""

    def next_event(self, now):
        """Virtual time of this block's next state change, or None."""
        return None

    def irq(self):
        """Interrupt line level."""
        return False


class Rcc(Block):
    """RCC (RM0444 §5.4): HSIRDY follows HSION, PLLRDY follows PLLON (§5.4.1),
    SWS follows SW (§5.4.3), LSIRDY follows LSION and the reset flags in
    RCC_CSR are sticky until RMVF (§5.4.25, offset 0x60)."""
    name = "RCC"
    CSR_FLAGS = 0xFE000000

    def __init__(self, machine):
        self.csr_flags = 0
        self.clock_key, self.clock_hz = None, HSI_HZ
        super().__init__(machine)

    def reset(self):
        super().reset()
        self.r[0x60] = self.csr_flags

    def read(self, off, now):
        v = self.r.get(off, 0)
        if off == 0x00:
            v &= ~((1 << 10) | (1 << 25))
            v |= (1 << 10) if v & (1 << 8) else 0
            v |= (1 << 25) if v & (1 << 24) else 0
        elif off == 0x08:
            v = (v & ~(7 << 3)) | ((v & 7) << 3)
        elif off == 0x60:
            v = (v & ~2) | (2 if v & 1 else 0)
        return v

    def write(self, off, val, now):
        if off == 0x60:
            if val & (1 << 23):
                self.csr_flags = 0
            val = (val & 0x1) | self.csr_flags
        super().write(off, val, now)

    def set_reset_flags(self, flags):
        """A reset of the given kinds: flags accumulate until RMVF."""
        self.csr_flags |= flags

    def sysclk(self):
        """SYSCLK in Hz: HSI16 or PLLRCLK (§5.2.3, §5.4.4), from CFGR and PLLCFGR."""
        key = (self.r.get(0x08, 0) & 7, self.r.get(0x0C, 0))
        if key != self.clock_key:
            self.clock_key, self.clock_hz = key, self._sysclk()
        return self.clock_hz

    def _sysclk(self):
        """SYSCLK in Hz from the registers."""
        if (self.r.get(0x08, 0) & 7) != 2:
            return HSI_HZ
        pll = self.r.get(0x0C, 0)
        m = ((pll >> 4) & 7) + 1
        n = (pll >> 8) & 0x7F
        r = ((pll >> 29) & 7) + 1
        return HSI_HZ // m * n // r


class Flash(Block):
    """FLASH interface (RM0444 §3.3, registers §3.7): KEYR unlock sequence
    (§3.3.6, a wrong key locks CR until reset), page erase (§3.3.7) and
    double-word programming (§3.3.8) with BSY1 for the datasheet's
    durations, EOP (with EOPIE) and the error flags PGSERR, PGAERR,
    SIZERR, PROGERR, WRPERR. The array itself is machine.flash (bytes)."""
    name = "FLASH"
    SR, CR, KEYR = 0x10, 0x14, 0x08
    PGSERR, SIZERR, PGAERR, WRPERR, PROGERR = 1 << 7, 1 << 6, 1 << 5, 1 << 4, 1 << 3
    EOP, BSY1 = 1 << 0, 1 << 16

    def __init__(self, machine):
        self.ops = []            # [(start time, "erase" or "prog", page or offset)], kept over resets
        super().__init__(machine)

    def reset(self):
        super().reset()
        self.key_state = 0
        self.key_dead = False
        self.busy_until = 0
        self.pending = None      # (time, kind, args)
        self.half = None         # first word of a double word: (addr, value)

    def read(self, off, now):
        self.tick(now)  # BSY1 and EOP change together
        v = self.r.get(off, 0)
        if off == self.SR:
            v = (v & ~self.BSY1) | (self.BSY1 if now < self.busy_until else 0)
        return v

    def write(self, off, val, now):
        if off == self.KEYR:
            self._key(val)
        elif off == self.SR:
            self.r[self.SR] &= ~(val & 0xC3FB)          # rc_w1 flags
        elif off == self.CR:
            self._cr(val, now)
        elif off == 0x00:
            self.r[0] = val & 0x70F                      # ACR: latency reads back
        elif off == 0x18:
            self.r[0x18] &= ~(val & 0xC0000000)          # ECCR: ECCC/ECCD rc_w1 (§3.7.6)
        else:
            super().write(off, val, now)

    def _key(self, val):
        """KEY1 then KEY2 clears LOCK; anything else locks until reset."""
        if self.key_dead:
            return
        if self.key_state == 0 and val == 0x45670123:
            self.key_state = 1
        elif self.key_state == 1 and val == 0xCDEF89AB:
            self.key_state = 0
            self.r[self.CR] &= ~(1 << 31)
        else:
            self.key_dead = True
            self.r[self.CR] |= 1 << 31

    def _cr(self, val, now):
        """CR while unlocked; STRT with PER starts a page erase."""
        cr = self.r[self.CR]
        if cr & (1 << 31):
            return
        if now < self.busy_until:
            return  # §3.7.5: CR not writable while BSY1
        self.r[self.CR] = val & 0xDF071FFF & ~(1 << 16)  # §3.7.5 bits
        if val & (1 << 31):
            self.key_state = 0
        if val & (1 << 16) and val & 2:
            page = (val >> 3) & 0x3FF              # PNB[12:3], 10 bits (SVD)
            if self.r[self.SR] & 0xC3FA or page >= FLASH_SIZE // FLASH_PAGE:
                self.r[self.SR] |= self.PGSERR if page < FLASH_SIZE // FLASH_PAGE else self.WRPERR
                return
            self._start(now, FLASH_ERASE_NS, ("erase", page))

    def _start(self, now, dur, op):
        self.busy_until = now + dur
        self.pending = (self.busy_until, op)
        self.ops.append((now, op[0], op[1]))

    def array_write(self, addr, size, val, now):
        """A CPU store into the flash array (the machine undoes it in its
        RAM copy): only PG with word stores at a double word, back to back."""
        cr = self.r[self.CR]
        off = addr - FLASH_BASE
        if cr & (1 << 31) or not cr & 1 or now < self.busy_until:
            self.r[self.SR] |= self.PGSERR
            self.half = None
            return
        if size != 4:
            self.r[self.SR] |= self.SIZERR
            self.half = None
            return
        if self.half is None:
            if off % 8:
                self.r[self.SR] |= self.PGAERR
                return
            self.half = (off, val)
            return
        first_off, first_val = self.half
        self.half = None
        if off != first_off + 4:
            self.r[self.SR] |= self.PGAERR
            return
        cell = bytes(self.m.flash[first_off:first_off + 8])
        if cell != b"\xff" * 8:
            self.r[self.SR] |= self.PROGERR
            return
        data = first_val.to_bytes(4, "little") + val.to_bytes(4, "little")
        self._start(now, FLASH_PROG_NS, ("prog", first_off, data))

    def tick(self, now):
        if self.pending and now >= self.pending[0]:
            op = self.pending[1]
            self.pending = None
            if op[0] == "erase":
                start = op[1] * FLASH_PAGE
                self.m.flash_store(start, b"\xff" * FLASH_PAGE)
            else:
                self.m.flash_store(op[1], op[2])
            if self.r[self.CR] & (1 << 24):
                self.r[self.SR] |= self.EOP

    def next_event(self, now):
        return self.pending[0] if self.pending else None


class Gpio(Block):
    """GPIO port (RM0444 §7.4): BSRR/BRR act on ODR; IDR shows ODR for
    outputs and the pull for inputs (nothing drives the pins from outside)."""

    def read(self, off, now):
        if off == 0x10:  # IDR
            moder, pupdr, odr = self.r[0x00], self.r[0x0C], self.r[0x14]
            idr = 0
            for pin in range(16):
                mode, pull = (moder >> 2 * pin) & 3, (pupdr >> 2 * pin) & 3
                level = (odr >> pin) & 1 if mode in (1, 2) else (1 if pull == 1 else 0)
                idr |= level << pin
            return idr
        return self.r.get(off, 0)

    def write(self, off, val, now):
        if off == 0x18:
            self.r[0x14] = (self.r[0x14] | (val & 0xFFFF)) & ~(val >> 16)
        elif off == 0x28:
            self.r[0x14] &= ~(val & 0xFFFF)
        else:
            super().write(off, val, now)


class GpioA(Gpio):
    name = "GPIOA"


class GpioB(Gpio):
    name = "GPIOB"


class Usart(Block):
    """USART1 (RM0444 §33.5, registers §33.8), FIFO off, 8N1, 16x
    oversampling: bit time = BRR / PCLK (§33.5.7). TDR -> shift register
    -> wire, TXE/TC (§33.5.5); RXNE at the middle of the stop bit, ORE when
    RDR is still full, RDR read clears RXNE (§33.5.6); in HDSEL (§33.5.14)
    the receiver hears our own transmission when RE is set."""
    name = "USART1"
    CR1, CR3, BRR, ISR, ICR, RDR, TDR = 0x00, 0x08, 0x0C, 0x1C, 0x20, 0x24, 0x28
    RXNE, TC, TXE, ORE, FE = 1 << 5, 1 << 6, 1 << 7, 1 << 3, 1 << 1

    def __init__(self, machine):
        self.overruns = 0        # bytes lost to ORE since power-on, kept over resets
        super().__init__(machine)

    def reset(self):
        super().reset()
        self.tdr_full = False
        self.tdr = 0
        self.shift_end = None     # time the byte in the shift register leaves
        self.shift_byte = 0
        self.shift_start = 0
        self.rdr = 0
        self.flags = self.TC | self.TXE
        self.rx_queue = []        # [(stop-bit middle time, byte)] from the wire
        self.wire_out = []        # [(start time, byte)] sent by the MCU

    def bit_ns(self):
        """One bit in ns from BRR and PCLK (= SYSCLK, APB undivided)."""
        brr = self.r.get(self.BRR, 0) or 1
        return brr * NS / self.m.pclk()

    def enabled(self):
        """UE set: the USART runs at bit_ns()."""
        return bool(self.r[self.CR1] & 1)

    def read(self, off, now):
        if off == self.ISR:
            cr1 = self.r[self.CR1]
            ack = ((1 << 21) if cr1 & 8 else 0) | ((1 << 22) if cr1 & 4 else 0)
            return self.flags | (ack if cr1 & 1 else 0)
        if off == self.RDR:
            self.flags &= ~self.RXNE
            return self.rdr
        return self.r.get(off, 0)

    def write(self, off, val, now):
        if off == self.ICR:
            self.flags &= ~(val & (self.ORE | self.FE | 0x5 | self.TC | 0x10))
        elif off == self.TDR:
            if self.r[self.CR1] & 9 == 9:
                self.tdr, self.tdr_full = val & 0xFF, True
                self.flags &= ~(self.TXE | self.TC)
                self._load(now)
        else:
            super().write(off, val, now)

    def _load(self, now):
        """Moves TDR into an idle shift register."""
        if self.tdr_full and self.shift_end is None:
            self.shift_byte, self.tdr_full = self.tdr, False
            self.shift_start = now
            self.shift_end = now + 10 * self.bit_ns()
            self.flags |= self.TXE

    def receive_at(self, when, byte, framing_error=False):
        """A byte on the wire whose stop bit's middle is at `when`."""
        bisect.insort(self.rx_queue, (when, byte, framing_error))

    def _rx(self, byte, framing_error=False):
        """The receiver completes a byte (RE and UE set); a stop bit read 0
        also sets FE, the data still goes to RDR (§33.5.6)."""
        cr1 = self.r[self.CR1]
        if cr1 & 5 != 5:
            return
        if self.flags & self.RXNE:
            self.flags |= self.ORE
            self.overruns += 1    # the byte is lost (§33.5.6: RDR keeps the older one)
        else:
            self.rdr, self.flags = byte, self.flags | self.RXNE | (self.FE if framing_error else 0)

    def tick(self, now):
        while self.shift_end is not None and now >= self.shift_end:
            self.wire_out.append((self.shift_start, self.shift_byte))
            if self.r[self.CR3] & 8:
                self._rx(self.shift_byte)  # half duplex: own echo
            end = self.shift_end
            self.shift_end = None
            if self.tdr_full:
                self._load(end)
            else:
                self.flags |= self.TC
        while self.rx_queue and now >= self.rx_queue[0][0]:
            _when, byte, framing_error = self.rx_queue.pop(0)
            self._rx(byte, framing_error)

    def next_event(self, now):
        times = [t for t in (self.shift_end, self.rx_queue[0][0] if self.rx_queue else None) if t is not None]
        return min(times) if times else None

    def irq(self):
        cr1, cr3, f = self.r[self.CR1], self.r[self.CR3], self.flags
        return bool((cr1 & (1 << 5) and f & (self.RXNE | self.ORE)) or (cr1 & (1 << 6) and f & self.TC)
                    or (cr1 & (1 << 7) and f & self.TXE) or (cr3 & 1 and f & (self.ORE | self.FE | 4)))


class Tim(Block):
    """General-purpose timer (RM0444 §22.3-22.4), up-counting: CNT from the
    timer clock (= PCLK) through PSC (loaded at an update event, §22.3.1),
    wrapping at ARR; compare channel 1 sets CC1IF on a match (§22.3.7);
    EGR UG/CC1G (§22.4.6); SR is rc_w0 (§22.4.5); PWM mode 1 duty read out."""
    CR1, DIER, SR, EGR, CNT, PSC, ARR, CCR1 = 0x00, 0x0C, 0x10, 0x14, 0x24, 0x28, 0x2C, 0x34

    def reset(self):
        super().reset()
        self.psc_active = 0
        self.t0 = 0
        self.cnt0 = 0
        self.last = 0

    def count(self, now):
        """CNT at `now`."""
        if not self.r[self.CR1] & 1:
            return self.cnt0
        ticks = int((now - self.t0) * self.m.pclk() // (NS * (self.psc_active + 1)))
        top = self.r[self.ARR] + 1
        return (self.cnt0 + ticks) % top

    def _rebase(self, now, cnt=None):
        self.cnt0 = self.count(now) if cnt is None else cnt
        self.t0 = now

    def read(self, off, now):
        if off == self.CNT:
            return self.count(now)
        return self.r.get(off, 0)

    def write(self, off, val, now):
        if off == self.SR:
            self.r[self.SR] &= val
        elif off == self.EGR:
            if val & 1:
                self.psc_active = self.r[self.PSC]
                self._rebase(now, 0)
                self.r[self.SR] |= 1
            if val & 2:
                self.r[self.SR] |= 2
        elif off == self.CNT:
            self._rebase(now, val)
        elif off in (self.CR1, self.ARR):
            self._rebase(now)
            super().write(off, val, now)
        else:
            super().write(off, val, now)

    def tick(self, now):
        cur = self.count(now)
        top = self.r[self.ARR] + 1
        ccr = self.r[self.CCR1]
        if self.r[self.CR1] & 1 and 0 < (ccr - self.last) % top <= (cur - self.last) % top:
            self.r[self.SR] |= 2
        self.last = cur

    def next_event(self, now):
        if not (self.r[self.CR1] & 1 and self.r[self.DIER] & 2):
            return None
        top = self.r[self.ARR] + 1
        delta = (self.r[self.CCR1] - self.count(now)) % top or top
        return now + delta * (self.psc_active + 1) * NS / self.m.pclk()

    def irq(self):
        return bool(self.r[self.DIER] & self.r[self.SR] & 0x1F)

    def duty(self, ch):
        """PWM mode 1 duty of channel ch (1..4) as CCRx / (ARR + 1), 0 if the output is off."""
        if not self.r[0x20] & (1 << 4 * (ch - 1)):
            return 0.0
        return min(1.0, self.r[0x30 + 4 * ch] / (self.r[self.ARR] + 1))


class Tim2(Tim):
    name = "TIM2"


class Tim3(Tim):
    name = "TIM3"


class Adc(Block):
    """ADC (RM0444 §15): ADVREGEN, ADCAL clears with EOCAL set (§15.3.3),
    ADEN sets ADRDY (§15.3.4), a CHSELR write sets CCRDY (§15.3.7), ADSTART
    in continuous scan mode converts the selected channels upward; with
    DMAEN each result goes to DMA1 channel 1 through DMAMUX (§15.6.5).
    Conversion time (SMP + 12.5 ADC cycles) x oversampling ratio, ADC clock
    PCLK/2 (CKMODE=01, §15.12.5). The inputs come from machine.sensors."""
    name = "ADC"
    ISR, CR, CFGR1, CFGR2, SMPR, CHSELR, DR = 0x00, 0x08, 0x0C, 0x10, 0x14, 0x28, 0x40
    SMP_CYCLES = (1.5, 3.5, 7.5, 12.5, 19.5, 39.5, 79.5, 160.5)

    def reset(self):
        super().reset()
        self.next_conv = None
        self.scan = []
        self.started_at = None   # virtual time of the first ADSTART (tests)

    def write(self, off, val, now):
        if off == self.ISR:
            self.r[self.ISR] &= ~val
        elif off == self.CR:
            cr = (self.r[self.CR] & ~(1 << 31)) | (val & 0x90000015)
            if val & (1 << 31):
                cr &= ~(1 << 31)
                self.r[self.ISR] |= 1 << 11      # EOCAL
            if val & 1:
                self.r[self.ISR] |= 1            # ADRDY
            self.r[self.CR] = cr
            if val & 4 and self.started_at is None:
                self.started_at = now
            if val & 4 and self.next_conv is None:
                self.scan = [ch for ch in range(19) if self.r[self.CHSELR] & (1 << ch)]
                self.next_conv = now + self.conv_ns()
        elif off == self.CHSELR:
            self.r[self.CHSELR] = val
            self.r[self.ISR] |= 1 << 13          # CCRDY
        else:
            super().write(off, val, now)

    def conv_ns(self):
        """One (oversampled) conversion in ns."""
        cfgr2 = self.r[self.CFGR2]
        ratio = 2 << ((cfgr2 >> 2) & 7) if cfgr2 & 1 else 1
        cycles = self.SMP_CYCLES[self.r[self.SMPR] & 7] + 12.5
        return cycles * ratio * NS / (self.m.pclk() / 2)

    def tick(self, now):
        while self.next_conv is not None and now >= self.next_conv and self.scan:
            ch = self.scan.pop(0)
            value = self.m.sample(ch, self.next_conv) & 0xFFF
            self.r[self.DR] = value
            if self.r[self.CFGR1] & 1:
                self.m.dma.request(5, value)
            if not self.scan:
                self.scan = [c for c in range(19) if self.r[self.CHSELR] & (1 << c)]
                if not self.r[self.CFGR1] & (1 << 13):
                    self.next_conv = None
                    break
            self.next_conv += self.conv_ns()

    def next_event(self, now):
        return self.next_conv


class Dma(Block):
    """DMA1 (RM0444 §10.4) channel 1 behind DMAMUX channel 0 (§11.3):
    a request of the DMAMUX-selected peripheral moves one item
    peripheral -> memory, CNDTR counts down and reloads in circular mode."""
    name = "DMA1"

    def reset(self):
        super().reset()
        self.cndtr_left = None

    def write(self, off, val, now):
        super().write(off, val, now)
        if off == 0x08 and val & 1:
            self.cndtr_left = self.r[0x0C]
            self.index = 0

    def request(self, source, value):
        """A DMA request from DMAMUX input `source` carrying `value`."""
        ccr = self.r[0x08]
        if not ccr & 1 or (self.m.dmamux.r[0x00] & 0x3F) != source or not self.cndtr_left:
            return
        size = 1 << ((ccr >> 10) & 3)
        addr = self.r[0x14] + (self.index * size if ccr & (1 << 7) else 0)
        self.m.mem_write(addr, value.to_bytes(4, "little")[:size])
        self.index += 1
        self.cndtr_left -= 1
        if self.cndtr_left == 0 and ccr & (1 << 5):
            self.cndtr_left, self.index = self.r[0x0C], 0

    def read(self, off, now):
        if off == 0x0C and self.cndtr_left is not None:
            return self.cndtr_left
        return self.r.get(off, 0)


class Dmamux(Block):
    name = "DMAMUX"


class Iwdg(Block):
    """IWDG (RM0444 §27.3): 0xCCCC starts it (it cannot be stopped), 0x5555
    opens PR/RLR, 0xAAAA reloads; PVU/RVU stay set for 5 LSI cycles after a
    write (§27.7.4); it counts (RLR+1) * 4 * 2^PR LSI periods after a reload
    and then resets the system."""
    name = "IWDG"
    KR, PR, RLR, SR = 0x00, 0x04, 0x08, 0x0C

    def reset(self):
        super().reset()
        self.running = False
        self.unlocked = False
        self.expiry = None
        self.sr_until = {1: 0, 2: 0}

    def read(self, off, now):
        if off == self.SR:
            return (1 if now < self.sr_until[1] else 0) | (2 if now < self.sr_until[2] else 0)
        return self.r.get(off, 0)

    def write(self, off, val, now):
        key = val & 0xFFFF
        if off == self.KR:
            if key == 0xCCCC:
                self.running = True
                self._reload(now)
            elif key == 0xAAAA:
                self._reload(now)
                self.unlocked = False
            elif key == 0x5555:
                self.unlocked = True
            else:
                self.unlocked = False
        elif off in (self.PR, self.RLR) and self.unlocked:
            self.r[off] = val & (7 if off == self.PR else 0xFFF)
            self.sr_until[1 if off == self.PR else 2] = now + 5 * NS // LSI_HZ

    def _reload(self, now):
        if self.running:
            period = 4 << min(self.r[self.PR], 6)
            self.expiry = now + (self.r[self.RLR] + 1) * period * NS // LSI_HZ

    def tick(self, now):
        if self.running and self.expiry is not None and now >= self.expiry:
            self.m.request_reset("iwdg")

    def next_event(self, now):
        return self.expiry if self.running else None
