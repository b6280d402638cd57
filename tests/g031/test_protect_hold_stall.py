#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The held-shaft stall of the protection bench (tests/bus/scenarios/
protect.txt, bus_check.py protect) replayed in virtual time on one virtual
STM32G031 running the shipped bootloader + application (docs/protocol.md
§5.2: stall = drive >= 0x3F's PWM while the shaft stays within 1.0 deg;
docs/virtual-g031.md "Found: the held-shaft stall that did not trip").

The bus test reaches that stall with a history its master's timing
shapes: the 0x65 that brings the shaft back from its end stop lands
earlier or later in the servo's time from run to run (the master is a
process of the host, the bus runs on virtual time). Here the same history
is played at fixed virtual times, with that 0x65 shifted by 0-3 ms; the
hold-phase load of protect.txt must trip the stall (hold action, release
by command) within 0x3F's 2.0 s + 1 s of its arrival at every shift.

    test_protect_hold_stall.py BUILD_DIR/boards/stm32g031
"""
import os
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
import g031_deps  # noqa: E402
g031_deps.require()
import vg031_bus  # noqa: E402

IMAGES = None
SCENARIO = os.path.join(ROOT, "tests", "bus", "scenarios", "protect.txt")
BAUD = 115200          # a fresh servo's baud (docs/protocol.md §1)
MS = 1_000_000
LOAD_KEY = 3           # sim/g031/g031_plant.py: the load on the horn, mN*m
ST_STALL = 0x08        # §4 status bit 3
# The replay's own timeline (ms on the plant's clock since power-on):
# the first stall's load pushes the free shaft onto its stop, goes, the
# shaft is sent back to 0 (+ the shift), then holds 2.5 s until the load.
PUSH_MS, PUSH_END_MS, MOVE_MS, LOAD_MS, LOAD_END_MS = 1000, 3000, 3000, 6000, 12000
TRIP_BY_MS = LOAD_MS + 2000 + 1000      # 0x3F's 2.0 s once the drive stands, + 1 s
SHIFTS_MS = (0, 1, 2, 3)


def frame(servo_id, cmd, adr=None, params=b""):
    """A command frame with its checksum (docs/protocol.md §2)."""
    body = bytes([servo_id, 2 + len(params) + (adr is not None), cmd])
    body += (bytes([adr]) if adr is not None else b"") + params
    return b"\xf9\xff" + body + bytes([~sum(body) & 0xFF])


def bench_loads():
    """The load_mnm values of protect.txt in order: (first stall's, hold phase's)."""
    loads = []
    with open(SCENARIO) as f:
        for line in f:
            words = line.split("#", 1)[0].split()
            if len(words) == 3 and words[1] == "load_mnm" and int(words[2]) != 0:
                loads.append(int(words[2]))
    assert len(loads) == 2, loads
    return loads[0], loads[1]


class Replay:
    """One servo (ID 1) on its own wire with the replay's load timeline."""

    def __init__(self, push_mnm, hold_mnm):
        images = tuple(os.path.join(IMAGES, n) for n in (
            "km-boot-stm32g031.elf", "km-servo-app-stm32g031.kmfw", "km-servo-app-stm32g031.elf"))
        events = [(PUSH_MS, LOAD_KEY, push_mnm), (PUSH_END_MS, LOAD_KEY, 0),
                  (LOAD_MS, LOAD_KEY, hold_mnm), (LOAD_END_MS, LOAD_KEY, 0)]
        self.servo = vg031_bus.Servo(1, images, None, "realistic", events)
        if not self.servo.provision(10):
            raise AssertionError("servo never answered on ID 1")
        self.m = self.servo.m

    def send(self, data, wait_ms=5):
        """Sends a frame now; the bytes the servo answered within wait_ms."""
        self.m.take_output()
        end = self.m.send(data, BAUD)
        self.m.run_until(end + wait_ms * MS)
        return bytes(b for _t, b in self.m.take_output())

    def write(self, addr, value):
        """A write (§3), then a read of the register: its value, or None."""
        self.send(frame(1, 0x03, addr, value))
        return self.read(addr, signed=False)

    def read(self, addr, signed=True):
        """A register's value (little-endian), or None without an answer."""
        out = self.send(frame(1, 0x02, addr))
        return int.from_bytes(out[6:-1], "little", signed=signed) if out[:3] == b"\xf9\xf5\x01" else None

    def status(self):
        """The status byte of a ping's answer (§4), or None."""
        out = self.send(frame(1, 0x01))
        return out[4] if out[:3] == b"\xf9\xf5\x01" and len(out) == 6 else None


def hold_stall(push_mnm, hold_mnm, shift_ms):
    """Plays the timeline with the move shifted; (trip time in ms or None,
    the trace [(ms, status, 0x46, 0x49)] from the load on)."""
    r = Replay(push_mnm, hold_mnm)
    # as bus_check.py: 0x3E 3 A, 2.0 s (the current protection stays out of it)
    assert r.write(0x3E, (3000).to_bytes(2, "little") + bytes([20])) == 3000 | 20 << 16
    r.m.run_until((MOVE_MS + shift_ms) * MS)
    r.send(frame(1, 0x03, 0x65, (0).to_bytes(2, "little", signed=True) + (500).to_bytes(2, "little")))
    r.m.run_until((MOVE_MS + 1500) * MS)
    assert r.write(0x33, b"\x08") == 0x08                      # stall released only by 0x36
    assert r.write(0x34, b"\x94") == 0x94                      # stall: hold
    trace = []
    for t_ms in range(LOAD_MS - 500, TRIP_BY_MS + 1, 50):
        r.m.run_until(t_ms * MS)
        st = r.status()
        trace.append((t_ms, st, r.read(0x46), r.read(0x49)))
        if st is not None and st & ST_STALL:
            return t_ms, trace
    return None, trace


class HoldStall(unittest.TestCase):
    def test_hold_phase_load_trips_the_stall_at_every_shift(self):
        push_mnm, hold_mnm = bench_loads()
        missed = []
        for shift in SHIFTS_MS:
            trip, trace = hold_stall(push_mnm, hold_mnm, shift)
            after = [pwm for t, _st, _pos, pwm in trace if t >= LOAD_MS + 500 and pwm is not None]
            print("load %d mN*m, move +%d ms: stall trip %s ms after the load; after 0.5 s 0x49 %s..%s, "
                  "0x46 %s at the end" % (hold_mnm, shift, None if trip is None else trip - LOAD_MS,
                                          min(after, default=None), max(after, default=None), trace[-1][2]))
            if trip is None:
                missed.append((shift, trace[-8:]))
        self.assertEqual(missed, [], "no stall trip by %d ms (shift, last samples (ms, status, 0x46, 0x49))"
                         % (TRIP_BY_MS - LOAD_MS))


def main():
    global IMAGES
    IMAGES = sys.argv.pop(1)
    unittest.main(verbosity=2)


if __name__ == "__main__":
    main()
