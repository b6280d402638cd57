# SPDX-License-Identifier: Apache-2.0
"""kmx trace (and tools/servo-session, its old name): a readable bus-master session against KINGMAX-protocol servos: prints
every frame sent and every answer, decoded with register names and units
(the host package host/kmx: its Bus, with a trace of the frames, and
docs/registers.json).

  kmx --bus tcp:127.0.0.1:7000 trace [--move]
  tools/servo-session --tcp 127.0.0.1:7000          (a bus from sim/bus/servo-bus)
  tools/servo-session --serial /dev/ttyUSB0 [--baud 115200]   (a real bus; needs python3-serial)
  tools/servo-session --bus pty:/dev/pts/3          (any kmx bus spec)

The session: scan with the super ID, read each servo's protocol and firmware
version and model, position, status and voltage. That is all it does unless
asked: it writes nothing and moves nothing, so it is safe on a real robot.

With --move (the demo's session, for an emulated bus or a servo on the
bench with nothing attached): write a setting and read it back, then put the
original value back (0x12 is user data: it would stay in flash); torque on,
move the first servo (0x65 out, 0x66 back, reading 0x46 until it arrives),
run it in motor mode for 0.5 s (0x70), send every servo its own target in
one 0x83 frame, torque off."""
import argparse
import sys
import time

from . import frame as fr
from .bus import Bus
from .errors import KmxError, NoAnswer
from .registers import RegisterMap

REGS = None  # the register description, loaded in main()
COLUMN = 36


class Session:
    """Prints what each step asks, the frames it sends and the answers,
    decoded."""

    def __init__(self, spec):
        self.bus = Bus(spec, timeout=0.2, retries=1, trace=self.on_frame)
        self.what = ""
        self.quiet = False

    def on_frame(self, direction, item):
        if self.quiet:
            return
        if direction == "tx":
            print("%-*s > %s" % (COLUMN, self.what, item.hex(" ").upper()))
            self.what = ""
        else:
            print("%-*s < %s   %s" % (COLUMN, "", item.to_bytes().hex(" ").upper(), describe(item)))

    def step(self, what, fn, *args, **kw):
        """Runs one bus call under a caption; a missing answer is printed, not fatal."""
        self.what = what
        try:
            return fn(*args, **kw)
        except NoAnswer:
            print("%-*s < (no answer)" % (COLUMN, ""))
            return None

    def get(self, dev_id, name):
        reg = REGS[name]
        data = self.step("read %s (0x%02X), id %d" % (reg.name, reg.address, dev_id), self.bus.read, dev_id, reg.address)
        return None if data is None else reg.decode(data)

    def set(self, dev_id, name, value):
        reg = REGS[name]
        data = reg.encode(value)
        self.step("write %s = %s, id %d" % (reg.name, reg.decode(data), dev_id),
                  self.bus.write, dev_id, reg.address, data)

    def position(self, dev_id, quiet=False):
        self.quiet = quiet
        try:
            v = self.get(dev_id, "position")
        finally:
            self.quiet = False
        return None if v is None else v.value

    def follow(self, dev_id, target, asked, quiet=False):
        """Reads the position until it is within 1.0° of target (5 s at
        most: an emulated servo on a loaded host runs late), as a master
        would, and says when it arrived."""
        start, pos = time.monotonic(), None
        while time.monotonic() - start < 5.0:
            pos = self.position(dev_id, quiet)
            if pos is not None:
                if not quiet:
                    print("%-*s   = %.1f ° after %d ms" % (COLUMN, "", pos, (time.monotonic() - start) * 1000))
                if abs(pos - target) <= 1.0:
                    break
            time.sleep(0.1)
        if pos is None or abs(pos - target) > 1.0:
            print("-- id %d did not arrive at %.1f ° (last read: %s)" %
                  (dev_id, target, "none" if pos is None else "%.1f °" % pos))
        else:
            print("-- id %d arrived: %.1f ° (asked %s)" % (dev_id, pos, asked))

    def watch(self, dev_id, seconds):
        """Position every 0.25 s for `seconds`: a motor run and its stop."""
        start = time.monotonic()
        while time.monotonic() - start < seconds:
            pos = self.position(dev_id, quiet=True)
            print("%-*s   position = %s at %d ms" % (COLUMN, "", "?" if pos is None else "%.1f °" % pos,
                                                     (time.monotonic() - start) * 1000))
            time.sleep(0.25)


def describe(f):
    """An answer in words: the status, or the register read with units."""
    if f.is_status:
        return "id %d status 0x%02X %s" % (f.id, f.status, ", ".join(fr.status_words(f.status)))
    if f.cmd != fr.READ:  # 0x78 update, 0x7F extension: no register behind the address byte
        return "id %d command 0x%02X, 0x%02X = %s" % (f.id, f.cmd, f.addr or 0, f.params.hex(" ").upper())
    try:
        reg = load_registers()[f.addr]
        return "id %d %s (0x%02X) = %s" % (f.id, reg.name, f.addr, reg.decode(f.params))
    except KmxError:
        return "id %d reg 0x%02X = %s" % (f.id, f.addr, f.params.hex(" ").upper())


def read_only(s, ids):
    """Reads what a servo is and where it stands: no write, no motion."""
    print("-- versions")
    for i in ids:
        for name in ("protocol_version", "firmware_version", "product_info"):
            s.get(i, name)
    print("-- position, status and voltage")
    for i in ids:
        for name in ("position", "status", "voltage"):
            s.get(i, name)


def setting_round_trip(s, first):
    """Writes 0x12 and reads it back, then restores what the servo had."""
    before = s.get(first, "response_delay")
    print("-- write a setting and read it back (response delay 250 µs), then restore it")
    s.set(first, "response_delay", 250)
    s.get(first, "response_delay")
    if before is not None:
        s.set(first, "response_delay", before.value)
        s.get(first, "response_delay")


def motion(s, ids):
    """Torque on, moves, a motor run, one 0x83 frame for all, torque off."""
    first = ids[0]
    print("-- move: torque on (0x64 = 2), then 0x65 to 45.0 ° in 500 ms")
    s.set(first, "torque_switch", 2)
    s.set(first, "move_time", "45, 500")
    s.follow(first, 45.0, "45.0 ° in 500 ms")
    print("-- back: 0x66 to 0.0 ° at 180 °/s")
    s.set(first, "move_speed", "0, 180")
    s.follow(first, 0.0, "0.0 ° at 180 °/s")
    print("-- motor mode: 0x70 PWM 500 for 0.5 s, then brake (it stops by itself)")
    s.set(first, "motor_advanced", "0x12, 5, 500")
    s.watch(first, 1.0)
    if len(ids) > 1:
        print("-- all at once: one 0x83 frame sends each servo its own 0x65 target")
        targets = {i: (-1) ** n * 30.0 * (1 + n // 2) for n, i in enumerate(ids[:8])}
        s.what = "0x83 of 0x64 = 2 to ids %s" % ",".join(map(str, targets))
        s.bus.multi_write(0x64, {i: b"\x02" for i in targets})
        s.what = "0x83 of 0x65, 500 ms, to %d servos" % len(targets)
        s.bus.multi_write(0x65, {i: REGS["move_time"].encode([t, 500]) for i, t in targets.items()})
        time.sleep(0.6)
        for i, t in targets.items():
            s.follow(i, t, "%.1f °" % t, quiet=True)
    s.what = "broadcast 0x64 = 0 (torque off)"
    s.bus.write(fr.ID_BROADCAST, 0x64, b"\x00")


def run(s, move):
    """The session: scan and read; with `move`, the write and motion part."""
    print("-- scan: ping with the super ID, every servo answers in its slot")
    s.what = "ping super ID"
    ids = [f.id for f in s.bus.scan_frames(timeout=1.0)]
    if not ids:
        raise NoAnswer("no servo answered the super-ID ping on %s" % s.bus.transport.spec)
    read_only(s, ids)
    if not move:
        print("-- read only: nothing written, nothing moved (--move runs the write and motion part)")
        return
    setting_round_trip(s, ids[0])
    motion(s, ids)
    print("-- status")
    for i in ids:
        s.get(i, "status")
        s.get(i, "voltage")


def load_registers(regmap=None):
    """The register description the session decodes with (loaded once)."""
    global REGS
    if REGS is None:
        REGS = regmap or RegisterMap.load()
    return REGS


def trace_line(direction, item):
    """One traced frame as the session prints it: '> bytes' for a frame sent,
    '< bytes   decoded' for an answer (kmx --trace)."""
    if direction == "tx":
        return "> %s" % bytes(item).hex(" ").upper()
    return "< %s   %s" % (item.to_bytes().hex(" ").upper(), describe(item))


def main(argv=None, prog="servo-session"):
    """servo-session's command line: --tcp, --serial (--baud) or --bus; --move."""
    ap = argparse.ArgumentParser(prog=prog, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--tcp", metavar="HOST:PORT", help="a bus from sim/bus/servo-bus")
    g.add_argument("--serial", metavar="DEVICE", help="serial port of a real bus adapter")
    g.add_argument("--bus", metavar="SPEC", help="any kmx bus spec (kmx --help)")
    ap.add_argument("--baud", type=int, default=115200, help="with --serial (default 115200)")
    ap.add_argument("--move", action="store_true",
                    help="also write a setting (restored afterwards) and move the servos: "
                         "only with nothing attached to them")
    args = ap.parse_args(argv)
    spec = args.bus or ("tcp:" + args.tcp if args.tcp else "serial:%s@%d" % (args.serial, args.baud))
    try:
        load_registers()
        run(Session(spec), args.move)
    except KmxError as e:
        sys.exit("%s: %s" % (prog, e))
    except KeyboardInterrupt:
        sys.exit("%s: interrupted" % prog)
    return 0
