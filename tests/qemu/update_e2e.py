#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Firmware update end to end on QEMU (docs/update.md, issue 12): three
emulated servos that boot through the bootloader (km-servo-boot-qemu-microbit.elf:
the bootloader with the v1 application in its factory slot) on one
sim/bus/servo-bus, then tools/servo-update:
  1. every servo answers 0x0C with the bootloader byte 0x10 and v1;
  2. an image for another board is refused by all three with nothing
     erased: they still run v1 (a BEGIN with the stm32g031 image);
  3. v2 to all three in one broadcast pass (figures printed);
  4. back to v1 with RESTARTS system resets (the standard restart frame,
     broadcast) and RESETS real ones (system_reset on one servo's QEMU
     monitor, inside a frame or the erase or program it causes) at random
     points of the pass; every servo answers a ping after each, and the
     update completes.
Prints "all checks passed" at the end; exit 1 on any failure.
    update_e2e.py [--restarts N] [--resets N] [--seed S] [--build-qemu DIR] [--build-stm32 DIR]
"""
import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
from kmx.bus import Bus  # noqa: E402
from kmx import frame as fr  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--restarts", type=int, default=3)
    ap.add_argument("--resets", type=int, default=4)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--build-qemu", default=os.environ.get("KM_BUILD_QEMU", os.path.join(REPO, "build/qemu")))
    ap.add_argument("--build-stm32", default=os.path.join(REPO, "build/stm32g031"))
    a = ap.parse_args()
    bdir = os.path.join(a.build_qemu, "boards/qemu-microbit")
    boot = os.path.join(bdir, "km-servo-boot-qemu-microbit.elf")
    v1 = os.path.join(bdir, "km-servo-app-qemu-microbit.kmfw")
    v2 = os.path.join(bdir, "km-servo-app-v2-qemu-microbit.kmfw")
    other = os.path.join(a.build_stm32, "boards/stm32g031/km-servo-app-stm32g031.kmfw")
    for f in (boot, v1, v2):
        if not os.path.isfile(f):
            print("missing %s: cmake --preset qemu && cmake --build --preset qemu" % f)
            return 1
    mon = tempfile.TemporaryDirectory(prefix="update-e2e-")
    bus_proc = subprocess.Popen([os.path.join(REPO, "sim/bus/servo-bus"), "--ids", "1,2,3", "--port", "0",
                                 "--image", boot, "--monitor-dir", mon.name],
                                stdout=subprocess.PIPE, text=True)
    failures = []
    try:
        line = bus_proc.stdout.readline().strip()
        if not line.startswith("ready "):
            print("servo-bus did not start: %r" % line)
            return 1
        spec = "tcp:" + line.split()[1]
        print("bus:", spec, flush=True)
        update = [os.path.join(REPO, "tools/servo-update"), "--bus", spec, "--ids", "1,2,3"]

        def versions():
            with Bus(spec, timeout=0.3) as bus:
                return {i: int.from_bytes(bus.read(i, 0x0C), "little") for i in (1, 2, 3)}

        v = versions()
        print("0x0C at start:", {i: "0x%08X" % x for i, x in v.items()})
        if any(x != 0x10100100 for x in v.values()):
            failures.append("1: not bootloader 0x10 + v1 at start")

        if os.path.isfile(other):
            r = subprocess.run(update + ["--attempts", "1", other], capture_output=True, text=True)
            print(r.stdout.strip())
            if r.returncode == 0 or r.stdout.count("wrong model") < 3:
                failures.append("2: the stm32g031 image was not refused by all three")
            # they are in their bootloaders now, the old image intact: START them
            with Bus(spec, timeout=0.3) as bus:
                bus.send_bytes(fr.encode_command(0xFE, 0x78, 0x07, bytes([0xE1, 0xE2, 0xE3, 0xE4])))
            time.sleep(1.0)
            v = versions()
            if any(x != 0x10100100 for x in v.values()):
                failures.append("2: after the refusal the servos do not run v1: %r" % v)
            else:
                print("2: the stm32g031 image refused by all three, v1 still boots")
        else:
            print("2: skipped (no %s; build the stm32g031 preset)" % other)

        r = subprocess.run(update + [v2], capture_output=True, text=True)
        print(r.stdout.strip())
        if r.returncode != 0 or versions() != {1: 0x10100102, 2: 0x10100102, 3: 0x10100102}:
            failures.append("3: v2 not on all three")

        r = subprocess.run(update + ["--restarts", str(a.restarts), "--seed", str(a.seed),
                                     "--resets", str(a.resets), "--monitor-dir", mon.name, v1],
                           capture_output=True, text=True)
        print(r.stdout.strip())
        if r.returncode != 0 or versions() != {1: 0x10100100, 2: 0x10100100, 3: 0x10100100}:
            failures.append("4: v1 with %d restarts and %d resets did not complete"
                            % (a.restarts, a.resets))
        if "%d restarts injected, %d resets injected, 0 times" % (a.restarts, a.resets) not in r.stdout:
            failures.append("4: not every restart or reset injected, or a servo unreachable after one")
    finally:
        bus_proc.send_signal(signal.SIGTERM)
        try:
            bus_proc.wait(10)
        except subprocess.TimeoutExpired:
            bus_proc.kill()
        mon.cleanup()
    for f in failures:
        print("FAIL", f)
    if failures:
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
