# SPDX-License-Identifier: Apache-2.0
"""Instruction classes and their Cortex-M0+ cycles beside the instruction
counts of the virtual G031 (which runs one instruction per clock): for a
few measured paths of the shipped stm32g031 image, how many instructions
of each class ran and what they cost on an M0+ (ARM DDI 0484C, Cortex-M0+
TRM §3.3), with the flash wait states of the application's clock and the
exception entries and returns. docs/figures.md prints the table
(tests/bench/m0/figures.py calls markdown()); the recorder, the cut into
idle-to-idle segments and the flash wait states are
tests/bench/m0/bench_realpath.py's (docs/benchmarks.md "Cycles"), handed
in as `bench`; its cycle model takes each instruction's cycles without
wait states from classify() here.

    markdown(bench, ELF) -> the section's lines
    paths(bench, ELF)    -> [(path, tally)]"""
import re

# Class, and its cycles without wait states (TRM §3.3), in table order.
CLASSES = ("ALU", "MUL", "load/store", "LDM/STM/PUSH/POP", "branch taken", "branch not taken",
           "BL", "BX/BLX", "system")
_COND = re.compile(r"b(eq|ne|cs|cc|hs|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le)")
FOUR_BYTES = ("bl", "mrs", "msr", "dmb", "dsb", "isb")


def classify(op, args, addr, nxt):
    """(class, cycles without flash wait states) of one executed
    instruction: ALU and hints 1, MULS 1 (the G0's single-cycle
    multiplier), LDR/STR 2, LDM/STM/PUSH 1+N, POP {.., pc} 3+N, a branch
    2 taken and 1 not, BL 3, BX/BLX 2, MRS/MSR/DMB/DSB/ISB 3, WFI 2, CPS 1.
    nxt is the address executed next (taken or not)."""
    jumped = nxt is not None and nxt != addr + (4 if op in FOUR_BYTES else 2)
    if op in ("push", "pop", "ldmia", "stmia", "ldm", "stm"):
        n = len([r for r in args[args.find("{") + 1:args.find("}")].split(",") if r.strip()])
        return "LDM/STM/PUSH/POP", (3 + n) if op == "pop" and "pc" in args else 1 + n
    if op.startswith(("ldr", "str")):
        return "load/store", 2
    if op == "bl":
        return "BL", 3
    if op in ("bx", "blx"):
        return "BX/BLX", 2
    if op == "b" or _COND.fullmatch(op):
        return ("branch taken", 2) if jumped else ("branch not taken", 1)
    if op in ("mrs", "msr", "dmb", "dsb", "isb"):
        return "system", 3
    if op in ("wfi", "cpsid", "cpsie"):
        return "system", 2 if op == "wfi" else 1
    if op.startswith("mul"):
        return "MUL", 1
    return "ALU", 1


def tally(b, lo, hi):
    """Per class (instructions, cycles) of the recorder's trace[lo:hi],
    plus the flash wait states (bench_realpath's model less the classes'
    own cycles) and the exception entries with their cycles."""
    out = {c: [0, 0] for c in CLASSES}
    model = 0
    tr = b.trace
    for i in range(lo, hi):
        nxt = tr[i + 1] if i + 1 < len(tr) else None
        op, args = b.d.op.get(tr[i], ("?", ""))
        cls, cyc = classify(op, args, tr[i], nxt)
        out[cls][0] += 1
        out[cls][1] += cyc
        model += b.d.cycles(tr[i], nxt)
    irqs = sum(1 for e in b.entries if lo <= e < hi)
    out["flash wait states"] = [None, model - sum(v[1] for v in out.values())]
    out["exception entry + return"] = [irqs, irqs * (b.IRQ_COST)]
    if out["flash wait states"][1] < 0 or (hi - lo, model + irqs * b.IRQ_COST) != b.cost(lo, hi):
        raise RuntimeError("g031_cycles: the classes do not add up to bench_realpath's count")
    return out


def _segments_of(b, f, wait_ms):
    """Sends frame f, returns (inner byte segments, the last byte's segment
    up to the answer armed): those with one received byte and no tick."""
    b.exchange(f, wait_ms)
    rx = b.d.sym["ISR_rx_byte"]
    inner, last, seen = [], None, 0
    for lo, hi in b.segments():
        nrx = sum(1 for i in range(lo, hi) if b.trace[i] == rx)
        index, seen = seen, seen + nrx
        if nrx != 1 or b.first(b.SHARED, lo, hi) is not None:
            continue
        if index == len(f) - 1:
            armed = b.armed(lo, hi)
            last = (lo, armed if armed is not None else hi)
        else:
            inner.append((lo, hi))
    return inner, last


def _add(total, part):
    """Sums two tallies."""
    for k, (n, c) in part.items():
        t = total.setdefault(k, [0 if n is not None else None, 0])
        t[0] = None if n is None else t[0] + n
        t[1] += c
    return total


def paths(bench, elf):
    """The measured paths: a ping's bytes inside the frame (all four, idle
    to idle), its last byte to the answer armed, the same for a read of
    0x0B, and one control tick of a move (idle to idle)."""
    b = bench.Bench(elf)
    b.IRQ_COST, b.SHARED = bench.IRQ_ENTRY + bench.IRQ_EXIT, bench.SHARED
    b.boot()
    out = []
    for what, f in (("ping 0x01", bench.frame(bench.OWN_ID, 0x01)),
                    ("read 0x02 of 0x0B", bench.frame(bench.OWN_ID, 0x02, b"\x0b"))):
        inner, last = _segments_of(b, f, 3)
        if last is None or not inner:
            raise RuntimeError("g031_cycles: %s not measured alone (a tick shared its wake-ups)" % what)
        total = {}
        for lo, hi in inner:
            _add(total, tally(b, lo, hi))
        out.append(("%s: its %d bytes before the last, idle to idle, summed" % (what, len(inner)), total))
        out.append(("%s: last byte -> answer armed" % what, tally(b, *last)))
    for f in (bench.frame(bench.OWN_ID, 0x03, b"\x64\x02"), bench.frame(bench.OWN_ID, 0x03, b"\x65\xc2\x01\xf4\x01")):
        b.exchange(f, 2)
    b.record(True)
    b.m.run_until(b.m.now + 5 * bench.MS)
    b.record(False)
    step = b.d.sym.get(bench.TICK[0]) or b.d.sym[bench.TICK[1]]
    ticks = [(lo, hi) for lo, hi in b.segments() if sum(1 for i in range(lo, hi) if b.trace[i] == step) == 1]
    if not ticks:
        raise RuntimeError("g031_cycles: no control tick measured")
    out.append(("control tick, moving (0x65 to +45.0 deg): the first of 5 ms, idle to idle", tally(b, *ticks[0])))
    return out


def markdown(bench, elf):
    """The docs/figures.md section."""
    cols = list(CLASSES) + ["flash wait states", "exception entry + return"]
    out = ["## Instruction classes and M0+ cycles (virtual G031, stand-alone image)", "",
           "The virtual G031 runs one instruction per clock; here each measured path's"
           " instructions are split into classes with their Cortex-M0+ cycles (ARM DDI"
           " 0484C §3.3: ALU 1, MULS 1, LDR/STR 2, LDM/STM/PUSH 1+N, POP {pc} 3+N, a"
           " branch 2 taken and 1 not, BL 3, BX/BLX 2, MRS/MSR/barriers 3, WFI 2, CPS 1),"
           " the application's flash wait states at its 64 MHz (FLASH_ACR.LATENCY 2:"
           " 2 per taken branch into flash and per literal load from flash; code in RAM"
           " pays none) and 15 + 13 cycles per exception entry and return; the model is"
           " docs/benchmarks.md's \"Cycles\". Each cell: instructions / cycles"
           " (sim/g031/g031_cycles.py).", "",
           "| path | instructions | est. M0+ cycles | " + " | ".join(cols) + " |",
           "|---" * (len(cols) + 3) + "|"]
    for what, t in paths(bench, elf):
        n = sum(t[c][0] for c in CLASSES)
        cyc = sum(v[1] for v in t.values())
        cells = []
        for c in cols:
            k, v = t[c]
            cells.append("%d" % v if k is None else ("%d / %d" % (k, v) if k else "—"))
        out.append("| %s | %d | %d | %s |" % (what, n, cyc, " | ".join(cells)))
    return out + [""]
