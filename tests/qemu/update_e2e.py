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
import subprocess
import sys
import time

from kmx.bus import Bus  # noqa: E402
from kmx import frame as fr  # noqa: E402
import update_rig as rig  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--restarts", type=int, default=3)
    ap.add_argument("--resets", type=int, default=4)
    ap.add_argument("--seed", type=int, default=3)
    rig.add_build_arg(ap)
    ap.add_argument("--build-stm32", default=os.path.join(rig.REPO, "build/stm32g031"))
    a = ap.parse_args()
    img = rig.images(a.build_qemu, [rig.BOOT, "km-servo-app-qemu-microbit.kmfw",
                                    "km-servo-app-v2-qemu-microbit.kmfw"])
    if img is None:
        return 1
    v1, v2 = img["km-servo-app-qemu-microbit.kmfw"], img["km-servo-app-v2-qemu-microbit.kmfw"]
    other = os.path.join(a.build_stm32, "boards/stm32g031/km-servo-app-stm32g031.kmfw")
    failures = []
    with rig.BootBus((1, 2, 3), img[rig.BOOT]) as boot_bus:
        spec = boot_bus.spec
        update = boot_bus.update_argv()

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
                                     "--resets", str(a.resets), "--monitor-dir", boot_bus.monitors.name, v1],
                           capture_output=True, text=True)
        print(r.stdout.strip())
        if r.returncode != 0 or versions() != {1: 0x10100100, 2: 0x10100100, 3: 0x10100100}:
            failures.append("4: v1 with %d restarts and %d resets did not complete"
                            % (a.restarts, a.resets))
        if "%d restarts injected, %d resets injected, 0 times" % (a.restarts, a.resets) not in r.stdout:
            failures.append("4: not every restart or reset injected, or a servo unreachable after one")
    return rig.report(failures)


if __name__ == "__main__":
    sys.exit(main())
