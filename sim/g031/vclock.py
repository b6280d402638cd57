# SPDX-License-Identifier: Apache-2.0
"""The virtual G031 bus's clock for a master in another process, so that
the master's timeouts and pauses are counted in the servos' virtual time
(docs/virtual-g031.md "Virtual time for the master").

The bus (vg031_bus.py --clock-file PATH) keeps its virtual time in PATH:
8 bytes, little-endian, nanoseconds, rewritten as the wire advances; the
next 8 bytes are the master's hold, the end of its latest sleep(). A
master process calls install(PATH) before it talks to the bus:
time.monotonic() then reads the virtual time and time.sleep() waits until
the virtual time has moved on by its argument. Because the bus never runs
ahead of real time, every real-time wait underneath (select, a queue's get,
a socket timeout) lasts at least as long as the virtual wait it stands
for; the callers that loop to a deadline (kmx.bus, pyserial's Timeout)
then wait on until the virtual deadline.

    python3 sim/g031/vclock.py CLOCK_FILE SCRIPT [ARGS...]

runs SCRIPT (a Python program, e.g. tools/servo-update) as __main__ with
the clock installed."""
import mmap
import os
import runpy
import sys
import time

STALL_S = 60.0   # the clock not moving for this long in real time: the bus is gone
STOPPED = (1 << 64) - 1   # what a bus that stopped leaves in its clock file (stop())
SIZE = 16                 # bytes 0-7: the bus's virtual time; 8-15: a master's hold (sleep())

real_monotonic = time.monotonic
real_sleep = time.sleep


class Clock:
    """Reads the bus's virtual time from its clock file."""

    def __init__(self, path):
        with open(path, "r+b") as f:
            self.map = mmap.mmap(f.fileno(), SIZE)
        self.seen, self.stopped_at = 0, None
        self.last = (self.ns(), real_monotonic())

    def _raw(self):
        """The clock file's value (read twice: the bus may be writing)."""
        while True:
            a = int.from_bytes(self.map[0:8], "little")
            if a == int.from_bytes(self.map[0:8], "little"):
                return a

    def ns(self):
        """Virtual nanoseconds; once the bus has stopped (STOPPED), the last
        virtual time seen goes on in real time, so that waiting for the bus
        process to end (subprocess's wait sleeps) is real time again."""
        raw = self._raw()
        if raw != STOPPED:
            self.seen = raw
            return raw
        if self.stopped_at is None:
            self.stopped_at = (self.seen, real_monotonic())
        return self.stopped_at[0] + int((real_monotonic() - self.stopped_at[1]) * 1e9)

    def monotonic(self):
        """Virtual seconds, for time.monotonic."""
        return self.ns() / 1e9

    def sleep(self, seconds):
        """Waits until the virtual time has advanced by `seconds`; a clock
        that stops for STALL_S real seconds raises RuntimeError. The end is
        published as the master's hold: the bus stops there until the
        master's next bytes (or its next hold), so what the master sends on
        waking goes on the wire at the virtual time it woke, however long
        the host took to run it (docs/virtual-g031.md "Virtual time for the
        master")."""
        end = self.ns() + int(max(0.0, seconds) * 1e9)
        self.map[8:16] = end.to_bytes(8, "little")
        moved = (self.ns(), real_monotonic())
        while True:
            now = self.ns()
            if now >= end:
                return
            if now != moved[0]:
                moved = (now, real_monotonic())
            elif real_monotonic() - moved[1] > STALL_S:
                raise RuntimeError("the virtual bus clock stopped (is the bus still running?)")
            real_sleep(min((end - now) / 1e9, 0.01))


def install(path):
    """time.monotonic, time.sleep and pyserial's timeouts on the bus's
    virtual time, for the rest of this process."""
    clock = Clock(path)
    time.monotonic = clock.monotonic
    time.sleep = clock.sleep
    try:
        import serial.serialutil
        serial.serialutil.Timeout.TIME = staticmethod(clock.monotonic)
    except ImportError:
        pass
    return clock


def create(path):
    """The bus side: a zeroed clock file, mapped for writing; returns the map."""
    with open(path, "wb") as f:
        f.write(bytes(SIZE))
    fd = os.open(path, os.O_RDWR)
    try:
        return mmap.mmap(fd, SIZE)
    finally:
        os.close(fd)


def hold(clock_map):
    """The bus side: the virtual time a master sleeps until (0: none yet)."""
    return int.from_bytes(clock_map[8:16], "little")


def publish(clock_map, ns):
    """The bus side: its virtual time now."""
    clock_map[0:8] = int(ns).to_bytes(8, "little")


def stop(clock_map):
    """The bus side: the bus stops; its masters' clocks go on in real time."""
    clock_map[0:8] = STOPPED.to_bytes(8, "little")


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    install(argv[0])
    sys.argv = argv[1:]
    sys.path[0] = os.path.dirname(os.path.abspath(argv[1]))  # as `python3 SCRIPT` would have it
    runpy.run_path(argv[1], run_name="__main__")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
