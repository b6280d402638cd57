#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Criterion 4 over the bus (issue 20, docs/control-quality.md "Over the
bus"): a master streams 0x68 to host-sim (the realistic plant, its default)
through sim/bus/servo-bus with real frame timing, and reads back what a master
can see. A ramp at 90 deg/s from -60 to +60 deg, one frame every 20 ms (50
Hz) or 10 ms (100 Hz), each sent a uniform -5..+5 ms off its time (seeded,
never out of order), frame k dropped when k mod 17 = 8 (as bench_control's
criterion 4). Between frames the master reads 0x47 (speed, deg/s, the
servo's 20 ms window) and 0x48 (current, mA). From 300 ms after the first
frame to the last: the speed ripple (largest |0x47 - 90| / 90) and the
largest |0x48| over its mean. Wall-clock timing on a shared host: the
figures carry the host's own scheduling jitter on top of the asked one.
Prints one markdown line per rate; exit 1 only on a run it cannot make.
  usage: bench_bus_stream.py [--build-dir DIR]   (default build/host-sim)
with host, sim/bus, tests/bus and tests/conformance on PYTHONPATH, as
tools/bench/bench-control runs it."""
import argparse
import os
import random
import struct
import time

import bus_check  # tests/bus: its Bus, reads and writes (tests/conformance for its master)
from kmx import frame as kmbus

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

SPEED_DPS = 90
FROM_DDEG, TO_DDEG = -600, 600


def quiet_read(bus, addr):
    """A signed register read, printing nothing; None without an answer."""
    got = bus.exchange(kmbus.read(1, addr), 1, timeout=0.2, silent=True)
    if len(got) != 1 or got[0].addr != addr or not got[0].params:
        return None
    return int.from_bytes(got[0].params, "little", signed=True)


def stream(bus, period_ms, rng):
    """One ramp as 0x68 frames; the (t, speed, current) samples read between them."""
    bus_check.write0(bus, 1, 0x65, struct.pack("<hH", FROM_DDEG, 500))
    time.sleep(1.5)
    n = (TO_DDEG - FROM_DDEG) * 1000 // (SPEED_DPS * 10) // period_ms
    t0 = time.monotonic() + 0.05
    last_send = 0.0
    samples = []
    dropped = 0
    for k in range(n + 1):
        due = t0 + (k * period_ms + rng.randint(-5, 5)) / 1000.0
        due = max(due, last_send + 0.001)
        while time.monotonic() < due:
            v, i = quiet_read(bus, 0x47), quiet_read(bus, 0x48)
            if v is not None and i is not None:
                samples.append((time.monotonic() - t0, v, i))
        last_send = time.monotonic()
        if k % 17 == 8:
            dropped += 1
            continue
        target = FROM_DDEG + (TO_DDEG - FROM_DDEG) * k // n
        bus.send(kmbus.write(1, 0x68, struct.pack("<h", target)))
    return samples, n + 1, dropped, (n * period_ms) / 1000.0


def figures(samples, end_s):
    """Speed ripple and current peak over mean from 300 ms to the last frame."""
    win = [s for s in samples if 0.3 <= s[0] <= end_s]
    if not win:
        raise SystemExit("bench_bus_stream: no samples in the window")
    speeds = [s[1] for s in win]
    cur = [abs(s[2]) for s in win]
    ripple = max(abs(v - SPEED_DPS) for v in speeds) * 100.0 / SPEED_DPS
    mean = sum(cur) / len(cur)
    return ripple, min(speeds), max(speeds), max(cur), mean, len(win)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build-dir", default=os.path.join(ROOT, "build", "host-sim"))
    a = ap.parse_args()
    opts = argparse.Namespace(gap_floor_us=None, build_dir=a.build_dir, product=None, scenario=None,
                              paced=False)
    bus = bus_check.Bus("host-sim", [1], opts)
    try:
        if not bus_check.wait_ping(bus, 1):
            raise SystemExit("bench_bus_stream: the servo does not answer")
        bus_check.write0(bus, 1, 0x11, b"\x02")  # response level 0: writes are not answered
        bus_check.write0(bus, 1, 0x64, b"\x02")
        rng = random.Random(20)
        for period in (20, 10):
            samples, frames, dropped, end_s = stream(bus, period, rng)
            ripple, vmin, vmax, peak, mean, n = figures(samples, end_s)
            print("- bus: 0x68 at %d Hz, ±5 ms, 1 frame in 17 dropped (%d frames, %d dropped), sent by a master "
                  "through sim/bus/servo-bus to host-sim in real time: 0x47 %d..%d °/s (ripple ±%.0f %%), 0x48 "
                  "peak %d mA over a mean of %.0f mA (%.1fx); %d samples between the frames"
                  % (1000 // period, frames, dropped, vmin, vmax, ripple, peak, mean, peak / max(mean, 1.0), n))
    finally:
        bus.close()


if __name__ == "__main__":
    main()
