#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The firmware's hot paths measured on the path the bytes really take, in
ARMv6-M instructions and estimated Cortex-M0+ cycles (docs/benchmarks.md).

Runs the shipped stm32g031 image (km-servo-stm32g031.elf, unmodified) on
the virtual STM32G031 (sim/g031, unicorn) in virtual time: bytes reach the
USART1 receiver at their real bit timing and go through the real receive
interrupt, queue and main loop; the control tick runs with the board's
ADC/DMA sensor read and TIM3 motor drive. During each measured window a
code hook records every instruction executed; the window is cut into
idle-to-idle segments at the image's WFI instructions and at the returns
from a handler into sleep-on-exit:

  per byte      a byte that does not end a frame, at 115200 baud: every
                instruction from the sleep before its interrupt to the next
                sleep, a WFI or the handler's return into sleep-on-exit
                (interrupt, and whatever main-loop work it causes);
  last byte     from the WFI before a frame's last byte to the entry of
                km_hal_timer_at (the answer timer armed), or to the next WFI
                for a frame with no answer;
  control tick  the segment that runs km_control_step (SysTick wake-up,
                sensor read, step, live values, motor drive), for every
                tick of a span on a fresh machine whose shaft is the plant
                (sim/plant): 800 ms torque off, 800 ms from a 0x65 move's
                arrival (speeding up, cruise, braking, settling, hold), a
                200 ms 0x68 stream; the worst, its tick and phase, the
                mean, and where the worst tick's instructions go by
                (innermost, inlining told apart) source function.

Cycles: each instruction's Cortex-M0+ count (ARM DDI 0484C §3.3: loads and
stores 2, taken branches 2, BL 3, PUSH/POP 1+N, POP {pc} 3+N, MSR/MRS/DMB
3, MULS 1), plus the board's flash wait states at its clock (64 MHz: 2)
for each taken branch into flash and each load from flash (the prefetch
hides sequential fetches; the cache is not modelled, so this is an upper
estimate), plus 15 cycles per interrupt entry and 13 per return (not
instructions, done by the core). Method: docs/benchmarks.md.

    PYTHONPATH=sim/g031 /usr/bin/python3 tests/bench/m0/bench_realpath.py BUILD_DIR [--base DIR] [--json OUT]

BUILD_DIR holds km-servo-stm32g031.elf (the stm32g031 preset's
build/stm32g031/boards/stm32g031). Prints a table; --json writes the figures
for tools that generate docs. Fails on a missing measurement or an answer
the image did not give; with --check also as its help says. An image
built without 0x82 (KM_G031_MULTI_READ=OFF, the 32 KiB build) does not
answer one listing it alone: the table says 0x82 is not built, and there
are no 0x82 figures."""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys

try:
    import g031_deps  # sim/g031, on PYTHONPATH (the command above; CTest sets it)
except ImportError:
    sys.exit("bench_realpath: sim/g031 is not on PYTHONPATH: run it as"
             " PYTHONPATH=sim/g031 /usr/bin/python3 ... (docs/benchmarks.md)")
g031_deps.require()
import vg031  # noqa: E402
import g031_cycles  # noqa: E402
import g031_plant  # noqa: E402
from unicorn import UC_HOOK_CODE  # noqa: E402

MS = 1_000_000
BAUD = 115200
FLASH_LO, FLASH_HI = 0x08000000, 0x08010000
FLASH_WS = 2          # 64 MHz: FLASH_ACR.LATENCY = 2 (boards/stm32g031/system.c)
IRQ_ENTRY, IRQ_EXIT = 15, 13
OWN_ID = 0            # a fresh servo (docs/protocol.md §1)
TARGET_BYTE, TARGET_LAST, TARGET_TICK = 60, 1500, 2000
# --check: a servo not in a list pays at most this many instructions an
# entry (the scans as built, docs/benchmarks.md "Lists"; the target is 2).
LIST_ENTRY_MAX = {"0x83_of_0x64": 3.25, "0x83_of_0x68": 3.6, "0x83_of_0x65": 3.75, "0x82_of_0x46": 1.65}
# Landmarks that survive LTO's inlining: a control tick calls km_control_step,
# or, inlined, runs prv_control_tick (kept a function for this) once; a
# main-loop pass asks prv_restart_ready; a
# frame handed to the dispatcher goes through km_servo_handle_view or
# prv_on_events.
TICK = ("km_control_step", "prv_control_tick")
# What tells a tick sharing a byte's or a frame's wake-up: the tick itself
# (a byte's wake-up that finds the tick due runs it without SysTick), or
# the 1 kHz wake-up.
SHARED = ("km_control_step", "prv_control_tick", "SysTick_Handler")
PASS = ("km_parser_feed_bytes", "prv_restart_ready")
DISPATCH = ("km_servo_handle_view", "prv_on_events")

_LIT = re.compile(r"\[pc")


def frame(servo_id, cmd, body=b"", response=False):
    """A frame with its checksum (docs/protocol.md §2)."""
    inner = bytes([servo_id, 2 + len(body), cmd]) + body
    return (b"\xf9\xf5" if response else b"\xf9\xff") + inner + bytes([~sum(inner) & 0xFF])


class Disasm:
    """Each instruction of the image: its mnemonic and cycle class."""

    def __init__(self, elf):
        out = subprocess.run(["arm-none-eabi-objdump", "-d", "--no-show-raw-insn", elf],
                             check=True, capture_output=True, text=True).stdout
        self.op = {}
        for line in out.splitlines():
            m = re.match(r"^\s*([0-9a-f]+):\s+(\S+)\s*(.*)$", line)
            if m and not m.group(2).startswith("."):
                self.op[int(m.group(1), 16)] = (m.group(2).split(".")[0], m.group(3))
        self.sym = {}
        out = subprocess.run(["arm-none-eabi-nm", "--defined-only", elf], check=True,
                             capture_output=True, text=True).stdout
        for line in out.splitlines():
            f = line.split()
            if len(f) == 3 and f[1] in "tTwW":
                # a clone under LTO or IPA (name.lto_priv.0, .constprop.0) answers to its name
                base = re.sub(r"(\.(lto_priv|constprop|isra|part)\.\d+)+$", "", f[2])
                self.sym.setdefault(f[2], int(f[0], 16) & ~1)
                self.sym.setdefault(base, int(f[0], 16) & ~1)

    def cycles(self, addr, nxt):
        """Estimated M0+ cycles of the instruction at addr, the next one
        executed being at nxt: its class's cycles (sim/g031/g031_cycles.py,
        TRM §3.3) and the flash wait states, a literal load from flash and
        the refill after a jump that writes the pc into flash."""
        op, args = self.op.get(addr, ("?", ""))
        cls, cyc = g031_cycles.classify(op, args, addr, nxt)
        if op.startswith("ldr") and _LIT.search(args) and FLASH_LO <= addr < FLASH_HI:
            cyc += FLASH_WS
        writes_pc = (cls in ("branch taken", "BL", "BX/BLX") or (op == "pop" and "pc" in args)
                     or (op.startswith("ldr") and "pc" in args.split(",")[0]))
        jumped = nxt is not None and nxt != addr + (4 if op in g031_cycles.FOUR_BYTES else 2)
        if writes_pc and jumped and FLASH_LO <= nxt < FLASH_HI:
            cyc += FLASH_WS
        return cyc


class Bench:
    """The machine, its recorder and the image's landmarks."""

    def __init__(self, elf, plant=None):
        self.d = Disasm(elf)
        self.m = vg031.Machine(vg031.flash_from_images(elf=elf), elves=[elf], plant=plant)
        self.trace = []         # executed PCs, while recording
        self.entries = []       # trace index of each exception entry while recording
        self.sleeps = []        # trace index after each return into sleep-on-exit while recording
        self.hook = None
        self.wfi = self.m.wfi_sites
        enter, leave = self.m._enter, self.m._exit

        def counting_enter(exc, ret_pc):
            if self.hook is not None:
                self.entries.append(len(self.trace))
            return enter(exc, ret_pc)

        def noting_exit(exc_return):
            asleep = leave(exc_return)
            if asleep and self.hook is not None:
                self.sleeps.append(len(self.trace))
            return asleep
        self.m._enter = counting_enter
        self.m._exit = noting_exit
        self.poll = self.d.sym["km_app_poll"]
        # libgcc's division entries (ARM EABI names and their aliases)
        self.divs = {a for n, a in self.d.sym.items()
                     if re.fullmatch(r"__(aeabi_u?i?l?div(mod)?|u?div[sd]i3|u?divmod[sd]i4|u?mod[sd]i3)", n)}

    def record(self, on):
        uc = self.m.uc
        if on and self.hook is None:
            self.trace, self.entries, self.sleeps = [], [], []
            tr = self.trace
            self.hook = uc.hook_add(UC_HOOK_CODE, lambda _uc, a, _s, _u: tr.append(a))
            uc.ctl_remove_cache(FLASH_LO, FLASH_HI)
            uc.ctl_remove_cache(0x20000000, 0x20002000)
        elif not on and self.hook is not None:
            uc.hook_del(self.hook)
            self.hook = None
            uc.ctl_remove_cache(FLASH_LO, FLASH_HI)
            uc.ctl_remove_cache(0x20000000, 0x20002000)

    def boot(self):
        seen = []
        self.m.watches[self.poll] = seen
        self.m.uc.hook_add(UC_HOOK_CODE, lambda *a: seen.append(1) if not seen else None, None,
                           self.poll, self.poll)
        if not self.m.run_until(self.m.now + 200 * MS, stop=lambda: bool(seen)):
            sys.exit("bench_realpath: the image never reached km_app_poll")
        self.m.run_until(self.m.now + 20 * MS)

    def segments(self):
        """(start, end) trace indices of each idle-to-idle segment: a WFI,
        or a handler's return into sleep-on-exit (SCR.SLEEPONEXIT), ends
        one; the instruction after it starts the next."""
        cuts = sorted([i + 1 for i, a in enumerate(self.trace) if a in self.wfi] + self.sleeps)
        out, start = [], 0
        for c in cuts:
            out.append((start, c))
            start = c
        return out

    def cost(self, lo, hi):
        """(instructions, estimated cycles) of trace[lo:hi] with its interrupt entries."""
        tr = self.trace
        cyc = sum(self.d.cycles(tr[i], tr[i + 1] if i + 1 < len(tr) else None) for i in range(lo, hi))
        irqs = sum(1 for e in self.entries if lo <= e < hi)
        return hi - lo, cyc + irqs * (IRQ_ENTRY + IRQ_EXIT)

    def first(self, name, lo, hi):
        """Trace index of the first entry of `name` (or of the first of a
        tuple of names the image has: LTO inlines some) in trace[lo:hi]."""
        names = name if isinstance(name, tuple) else (name,)
        want = {self.d.sym[n] for n in names if n in self.d.sym}
        for i in range(lo, hi):
            if self.trace[i] in want:
                return i
        return None

    def armed(self, lo, hi):
        """Where the answer is armed: the entry of km_hal_timer_at, or, with
        it inlined (LTO), the return of prv_arm_answer (prv_try_schedule_answer
        before the application's one answer buffer)."""
        i = self.first("km_hal_timer_at", lo, hi)
        if i is not None or "km_hal_timer_at" in self.d.sym:
            return i
        i = self.first(("prv_arm_answer", "prv_try_schedule_answer"), lo, hi)
        if i is None:
            return None
        return self.returned(i, hi)

    def returned(self, i, hi):
        """Trace index, before hi, where the function entered at trace[i]
        returns (the instruction after the bl that called it), or None."""
        ret = self.trace[i - 1] + 4  # after the bl that called it
        return next((j for j in range(i, hi) if self.trace[j] == ret), None)

    def inclusive(self, name, lo, hi):
        """Instructions and cycles from the entry of `name` to its return
        (the instruction after its call site), inside trace[lo:hi]."""
        i = self.first(name, lo, hi)
        j = None if i is None else self.returned(i, hi)
        return None if j is None else self.cost(i, j)

    def clear_of_tick(self, data):
        """Waits (not recording) so that `data`, sent next, ends 0.4 ms
        after a SysTick: the control tick, due just before each 1 kHz
        wake-up, then never shares the last byte's pass (docs/benchmarks.md
        "Per byte": only a frame's end and that wake-up run the main loop)."""
        scs = self.m.scs
        if scs.syst_next is None:
            return
        period = scs._syst_period()
        end = self.m.now + len(data) * 10 * 1e9 / BAUD
        self.m.run_until(self.m.now + int((scs.syst_next + 0.4 * period - end) % period))

    def exchange(self, data, wait_ms):
        """Sends data at BAUD, records until wait_ms after its last stop bit,
        returns (answer bytes)."""
        self.m.take_output()
        self.record(True)
        end = self.m.send(data, BAUD)
        self.m.run_until(end + wait_ms * MS)
        self.record(False)
        return bytes(b for _t, b in self.m.take_output())


def per_byte(b, rows, figs):
    """Bytes that do not end a frame, one at a time at 115200, and the
    frames' last bytes to the answer armed."""
    mix = [frame(OWN_ID, 0x01), frame(OWN_ID, 0x02, b"\x13"), frame(5, 0x02, b"\x13"),
           frame(5, 0x02, bytes([0x13, 0x34, 0x12]), response=True), frame(OWN_ID, 0x03, b"\x5b\x01"),
           frame(OWN_ID, 0x02, b"\x0a")]
    inner, lasts, parsed = [], [], 0
    rx = b.d.sym["ISR_rx_byte"]
    for rep in range(3):
        for f in mix:
            ans = b.exchange(f, 3)
            ours = f[1] == 0xFF and f[2] == OWN_ID and f[4] in (0x01, 0x02)
            if ours and not ans:
                sys.exit("bench_realpath: no answer to %s" % f.hex())
            seen = 0  # bytes of f received before the segment
            for lo, hi in b.segments():
                nrx = sum(1 for i in range(lo, hi) if b.trace[i] == rx)
                irq = [e for e in b.entries if lo <= e < hi]
                index, seen = seen, seen + nrx
                if nrx != 1 or len(irq) != 1 or b.first(SHARED, lo, hi) is not None:
                    continue  # no byte, or a byte sharing its wake-up with the tick
                if index != len(f) - 1 and b.first(TICK, lo, hi) is not None:
                    continue  # a byte's wake-up that ran the tick
                if index == len(f) - 1:
                    armed = b.armed(lo, hi)
                    lasts.append(b.cost(lo, armed if armed is not None else hi) + (f[4], f[1], armed is not None))
                else:
                    inner.append(b.cost(lo, hi))
                    parsed += b.first(PASS, lo, hi) is not None
    figs["byte_parsed"] = parsed
    if not inner:
        sys.exit("bench_realpath: no byte measured alone")
    n = len(inner)
    ins = sum(c[0] for c in inner) / n
    cyc = sum(c[1] for c in inner) / n
    figs["byte_instructions"], figs["byte_cycles"] = round(ins, 1), round(cyc, 1)
    figs["byte_max_instructions"] = max(c[0] for c in inner)
    busy = cyc * (BAUD / 10) / 16e6 * 100
    figs["byte_busy_percent_16mhz"] = round(busy, 1)
    rows.append(("per byte inside a frame, idle to idle, 115200 baud (%d bytes): mean / max" % n,
                 "%.1f / %d" % (ins, figs["byte_max_instructions"]), "%.0f" % cyc, "<= %d" % TARGET_BYTE))
    rows.append(("listening to a busy 115200 bus (11,520 B/s): share of a 16 MHz M0+", "",
                 "%.1f %%" % busy, "<= 10 %"))
    worst = {}
    for ins_, cyc_, cmd, hdr1, armed in lasts:
        k = (cmd if hdr1 == 0xFF else None, armed)
        if k not in worst or ins_ > worst[k][0]:
            worst[k] = (ins_, cyc_)
    for (cmd, armed), (ins_, cyc_) in sorted(worst.items(), key=lambda kv: (kv[0][0] is None, kv[0])):
        what = "answer armed" if armed else "next WFI (no answer)"
        kind = "command 0x%02X" % cmd if cmd is not None else "another servo's answer"
        rows.append(("last byte -> %s: %s, worst of the mix" % (what, kind),
                     "%d" % ins_, "%d" % cyc_, "<= %d" % TARGET_LAST))
        figs["last_%s_%s" % ("0x%02X" % cmd if cmd is not None else "answer", "armed" if armed else "idle")] = [
            ins_, cyc_]
    rows.append(("bytes inside a frame that ran the parser (should be none)", "%d of %d" % (parsed, n), "",
                 "0"))


def per_entry(pts):
    """Instructions (or cycles) an entry: the least-squares slope over the
    list lengths of the count from the dispatcher's entry on (the parser's
    copy of the bytes since the previous wake-up before it varies with
    timing, not with the list)."""
    if len(pts) < 2:
        return 0.0
    return statistics.linear_regression([n for n, _ in pts], [v for _, v in pts]).slope


def lists(b, rows, figs, step):
    """0x83 and 0x82 at every list length (every `step`-th), this servo last
    or absent: the last byte to the answer armed or to the next WFI."""
    out, no_0x82 = {}, False
    lengths = (("0x83 of 0x64", 1, 125), ("0x83 of 0x68", 2, 83), ("0x83 of 0x65", 4, 50), ("0x82 of 0x46", 0, 250))
    for kind, k, maxn in lengths:
        for n in list(range(1, maxn + 1, step)) + [maxn]:
            for ours in (True, False):
                if no_0x82 and kind.startswith("0x82"):
                    break
                if kind.startswith("0x83"):
                    body = bytes([int(kind[-4:], 16), k])
                    for i in range(n):
                        sid = OWN_ID if (ours and i == n - 1) else i + 1
                        body += bytes([sid]) + {1: b"\x00", 2: b"\x00\x00", 4: b"\x00\x00\xe8\x03"}[k]
                    f = frame(0xFE, 0x83, body)
                else:
                    ids = [i + 1 for i in range(n)]
                    if ours:
                        ids[-1] = OWN_ID
                    f = frame(0xFE, 0x82, bytes([0x46] + ids))
                if len(f) > 256:
                    continue
                b.clear_of_tick(f)
                answer = b.exchange(f, 2)
                if kind.startswith("0x82") and ours and n == 1 and not answer:
                    no_0x82 = True  # not built in this image (below)
                    break
                got = None
                for lo, hi in b.segments():
                    at = b.first(DISPATCH, lo, hi)
                    if at is not None:
                        if b.first(SHARED, lo, hi) is not None:
                            break
                        armed = b.armed(lo, hi)
                        stop = armed if armed is not None else hi
                        got = b.cost(lo, stop) + (stop - at, b.cost(at, stop)[1])
                if got is not None:
                    out[(kind, ours, n)] = got
    for kind, _k, _maxn in lengths:
        for ours in (True, False):
            pts = sorted((n, v) for (kd, o, n), v in out.items() if kd == kind and o == ours)
            if not pts:
                continue
            n, (ins, cyc, _, _) = max(pts, key=lambda p: p[1][0])
            slope = per_entry([(m, v[2]) for m, v in pts])
            cyc_slope = per_entry([(m, v[3]) for m, v in pts])
            key = "%s_%s" % (kind.replace(" ", "_"), "ours" if ours else "absent")
            figs[key] = {"worst_n": n, "instructions": ins, "cycles": cyc, "per_entry": round(slope, 2),
                         "cycles_per_entry": round(cyc_slope, 2)}
            rows.append(("%s, %s, %d list lengths: worst (at %d) / per entry" %
                         (kind, "this servo last" if ours else "this servo not listed", len(pts), n),
                         "%d / %.2f" % (ins, slope), "%d / %.2f" % (cyc, cyc_slope),
                         "<= %d%s" % (TARGET_LAST, "" if ours else " / <= 2")))
    if no_0x82:
        # KM_G031_MULTI_READ=OFF (the 32 KiB build, docs/footprint.md "What
        # gives way"): 0x82 is an unsupported command there, nothing to measure.
        print("bench_realpath: 0x82 (multi-ID read) is not built in this image: no 0x82 figures", file=sys.stderr)
        rows.append(("0x82 (multi-ID read): not built in this image (KM_G031_MULTI_READ=OFF)", "-", "-", "-"))


TICK_SPAN_MS = 800   # a move of 500 ms, its arrival and settling, then hold
MOVE_MS = 500
STREAM_MS = 200      # 0x68 set-points, one every STREAM_EVERY_MS
STREAM_EVERY_MS = 10


class Funcs:
    """The function each address runs: the innermost source function, with
    what the compiler inlined told apart (addr2line -i on the image)."""

    def __init__(self, elf):
        self.elf = elf
        self.name = {}

    def of(self, addrs):
        """{address: innermost function} for the addresses (one addr2line run)."""
        need = sorted(set(addrs) - set(self.name))
        if need:
            out = subprocess.run(["arm-none-eabi-addr2line", "-a", "-i", "-f", "-e", self.elf]
                                 + ["%x" % a for a in need], check=True, capture_output=True, text=True).stdout
            lines = out.splitlines()
            for j, line in enumerate(lines):
                if line.startswith("0x") and j + 1 < len(lines):
                    self.name[int(line, 16)] = lines[j + 1]   # the innermost: first after the address
        return {a: self.name[a] for a in addrs}


def tick_segments(b):
    """Every control tick in the recording, in order: [lo, hi, ticks in the
    segment, shared with a frame's dispatch, tick number, frames dispatched
    before it, ticks since the last of them], numbered from the first tick
    after the first frame's dispatch (1), or from the recording's start
    without a frame."""
    step_at = b.d.sym[TICK[0]] if TICK[0] in b.d.sym else b.d.sym[TICK[1]]
    out, frames, since = [], 0, 0
    for lo, hi in b.segments():
        k = sum(1 for i in range(lo, hi) if b.trace[i] == step_at)
        if b.first(DISPATCH, lo, hi) is not None:
            frames, since = frames + 1, 0
        if k:
            since += 1
            out.append([lo, hi, k, since == 1 and frames > 0 and b.first(DISPATCH, lo, hi) is not None,
                        0, frames, since])
    first = next((n for n, seg in enumerate(out) if seg[5]), 0)
    for n, seg in enumerate(out):
        seg[4] = n + 1 - first
    return out


PHASES = ("start", "accelerating", "cruise", "braking", "settling", "hold")


def tick_divisions(b, seg):
    """Library divisions the tick itself calls in a segment: from the entry
    of prv_control_tick (or km_control_step) to its return; the rest of the
    wake-up (idle store work in the main loop) is not the tick."""
    lo, hi = seg[0], seg[1]
    n, i = 0, lo
    while i < hi:
        j = b.first(TICK[::-1], i, hi)
        if j is None:
            break
        end = b.returned(j, hi)
        end = hi if end is None else end
        n += sum(1 for k in range(j, end) if b.trace[k] in b.divs)
        i = end
    return n


def phase_of(pos, n, target):
    """The phase of the move at tick n (1-based) from the shaft's position
    (0.1 deg) at each tick: by its speed over +-5 ticks against the peak."""
    v = [abs(pos[min(len(pos) - 1, i + 5)] - pos[max(0, i - 5)]) for i in range(len(pos))]
    vmax = max(v) or 1
    peak = v.index(vmax)
    i = max(0, min(len(pos) - 1, n - 1))
    moved_later = any(abs(pos[j] - pos[i]) > 2 for j in range(i, min(len(pos), i + 20)))
    if v[i] >= 0.9 * vmax:
        return "cruise"
    if i < peak:
        return "accelerating" if v[i] > 0 or moved_later else "start"
    if abs(pos[i] - target) > 10:
        return "braking"
    return "settling" if moved_later else "hold"


def tick_run(b, ms, send=(), every_ms=0):
    """Records `ms` ms, sending the frames of `send` (one every `every_ms`,
    the first at once, each clear of a tick): every tick in it, with the
    shaft position at each."""
    pos = []
    plant = b.m.plant
    b.m.take_output()
    b.record(True)
    t0 = b.m.now
    for j, f in enumerate(send):
        if j:
            b.m.run_until(t0 + j * every_ms * MS)
        b.clear_of_tick(f)
        b.m.run_until(b.m.send(f, BAUD) + MS // 2)
    # the shaft at each ms, sampled as the run goes
    step = MS
    while b.m.now < t0 + ms * MS:
        b.m.run_until(min(t0 + ms * MS, b.m.now + step))
        pos.append(plant.readings[0])
    b.record(False)
    return pos


def worst_by_phase(b, costs, pos, target):
    """{phase: the worst tick's instructions in it} of a move."""
    out = {}
    for (ins, _cyc), seg in costs:
        ph = phase_of(pos, seg[4], target)
        out[ph] = max(out.get(ph, 0), ins)
    return out


def by_function(b, funcs, seg, top=8):
    """The functions a tick's segment spent most instructions in:
    [(innermost source function, instructions)], the most first."""
    names = funcs.of(b.trace[seg[0]:seg[1]])
    count = {}
    for i in range(seg[0], seg[1]):
        f = names[b.trace[i]]
        count[f] = count.get(f, 0) + 1
    return sorted(count.items(), key=lambda kv: -kv[1])[:top]


def tick_figures(b, funcs, label, key, pos, target, rows, figs, every_ms=0):
    """The worst, mean and worst's place of every tick recorded, and where
    the worst tick's instructions go."""
    segs = tick_segments(b)
    if not segs:
        sys.exit("bench_realpath: no control tick measured (%s)" % label)
    alone = [s for s in segs if s[2] == 1 and not s[3]]
    costs = [(b.cost(s[0], s[1]), s) for s in alone]
    (ins, cyc), ws = max(costs, key=lambda c: c[0][0])
    mean = sum(c[0][0] for c in costs) / len(costs)
    n = ws[4]
    if target is not None:
        phase = phase_of(pos, n, target)
    elif every_ms:
        phase = "tick %d after set-point %d" % (ws[6], ws[5])
    else:
        phase = "idle"
    divs = max(tick_divisions(b, s) for s in segs)
    wake_divs = max(sum(1 for i in range(s[0], s[1]) if b.trace[i] in b.divs) for s in segs)
    per_phase = worst_by_phase(b, costs, pos, target) if target is not None else {}
    top = by_function(b, funcs, ws)
    figs[key] = {"instructions": ins, "cycles": cyc, "library_divisions": divs, "wake_up_divisions": wake_divs,
                 "ticks": len(segs), "measured": len(alone), "mean": round(mean, 1), "worst_tick": n,
                 "worst_phase": phase, "shared": sum(1 for s in segs if s[3]),
                 "double": sum(1 for s in segs if s[2] > 1), "worst_functions": top,
                 "worst_by_phase": per_phase, "shaft_end_ddeg": pos[-1]}
    rows.append(("control tick all in, idle to idle, %s: worst of every tick (%d; %d shared a frame's"
                 " wake-up, %d ran 2 ticks, left out), at tick %d (%s) / mean (library divisions: in a tick %d,"
                 " in a tick's wake-up %d)"
                 % (label, len(alone), figs[key]["shared"], figs[key]["double"], n, phase, divs, wake_divs),
                 "%d / %.0f" % (ins, mean), "%d" % cyc, "<= %d" % TARGET_TICK))
    if per_phase:
        rows.append(("  worst tick by phase: " + ", ".join("%s %d" % (ph, per_phase[ph]) for ph in PHASES
                                                            if ph in per_phase), "", "", ""))
    rows.append(("  worst tick's instructions by function: " +
                 ", ".join("%s %d" % kv for kv in top), "", "", ""))


def ticks(elf, rows, figs):
    """Every control tick, torque off and through a whole move (the
    command's arrival, speeding up, cruise, braking, settling, hold) and
    under a 0x68 stream, on a fresh machine with the plant (sim/plant) as
    the shaft: the same ticks whatever else the bench measured."""
    b = Bench(elf, plant=g031_plant.Plant("realistic"))
    b.boot()
    funcs = Funcs(elf)
    pos = tick_run(b, TICK_SPAN_MS)
    tick_figures(b, funcs, "torque off, %d ms" % TICK_SPAN_MS, "tick_torque_off", pos, None, rows, figs)
    b.exchange(frame(OWN_ID, 0x03, b"\x64\x02"), 20)
    move = frame(OWN_ID, 0x03, b"\x65\xc2\x01\xf4\x01")
    start = b.m.plant.readings[0]
    pos = tick_run(b, TICK_SPAN_MS, [move])
    tick_figures(b, funcs, "moving (0x64 = 2, 0x65 to +45.0 deg in %d ms from %+.1f deg), %d ms from the"
                 " command's arrival" % (MOVE_MS, start / 10, TICK_SPAN_MS), "tick_moving", pos, 450, rows, figs)
    pts = [frame(OWN_ID, 0x03, b"\x68" + (450 - 20 * j).to_bytes(2, "little", signed=True))
           for j in range(STREAM_MS // STREAM_EVERY_MS)]
    pos = tick_run(b, STREAM_MS, pts, STREAM_EVERY_MS)
    tick_figures(b, funcs, "0x68 stream (a set-point every %d ms, 45.0 -> 7.0 deg), %d ms"
                 % (STREAM_EVERY_MS, STREAM_MS), "tick_stream", pos, None, rows, figs, STREAM_EVERY_MS)


def measure(elf, only=("byte", "tick", "lists"), step=1):
    """Every figure: (rows of (figure, instructions, cycles, target), a
    dict of the values by key)."""
    b = Bench(elf)
    b.boot()
    rows, figs = [], {}
    if "byte" in only:
        per_byte(b, rows, figs)
    if "tick" in only:
        ticks(elf, rows, figs)
    if "lists" in only:
        lists(b, rows, figs, step)
    return rows, figs


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("build", help="directory holding km-servo-stm32g031.elf")
    ap.add_argument("--json", help="write the figures here")
    ap.add_argument("--step", type=int, default=1, help="list lengths: every N-th (default 1: all)")
    ap.add_argument("--only", default="byte,lists,tick")
    ap.add_argument("--check", action="store_true",
                    help="fail if a byte inside a frame ran the parser, a control tick called a library"
                         " division or a list scan costs more an entry than LIST_ENTRY_MAX"
                         " (docs/benchmarks.md \"Per byte\", \"Control tick\", \"Lists\")")
    a = ap.parse_args()
    elf = os.path.join(a.build, "km-servo-stm32g031.elf")
    if not os.path.exists(elf):
        sys.exit("bench_realpath: missing %s (cmake --build --preset stm32g031)" % elf)
    rows, figs = measure(elf, a.only.split(","), a.step)
    w = max(len(r[0]) for r in rows)
    print("%-*s | %14s | %10s | %s" % (w, "figure (stm32g031 image on sim/g031)", "instructions",
                                      "M0+ cycles", "target (instructions)"))
    for r in rows:
        print("%-*s | %14s | %10s | %s" % (w, r[0], r[1], r[2], r[3]))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(figs, f, indent=1, sort_keys=True)
    if a.check and figs.get("byte_parsed", 0):
        print("bench_realpath: %d bytes inside a frame ran the parser" % figs["byte_parsed"], file=sys.stderr)
        return 1
    slow = {k: figs[k + "_absent"]["per_entry"] for k in LIST_ENTRY_MAX
            if k + "_absent" in figs and figs[k + "_absent"]["per_entry"] > LIST_ENTRY_MAX[k]}
    if a.check and slow:
        print("bench_realpath: a list scan costs more an entry than %s: %s" % (LIST_ENTRY_MAX, slow),
              file=sys.stderr)
        return 1
    divs = {k: v["library_divisions"] for k, v in figs.items() if k.startswith("tick_")}
    if a.check and any(divs.values()):
        print("bench_realpath: a control tick called a library division (%s)" % divs, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
