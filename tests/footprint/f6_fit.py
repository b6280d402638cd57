#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The 32 KiB STM32G031F6 build (docs/footprint.md "STM32G031F6") keeps
fitting: configures `cmake --preset stm32g031 -DKM_G031_FLASH_KB=32` in its
own build directory, builds the images that fit today with their
image-check, which in that build enforces the budget (--enforce-budget:
bootloader <= 4,096 B, RAM <= 6 KiB), and runs that bootloader alone on
the virtual G031 (sim/g031): with no application and no store reader it
answers at ID 1, 115200 (docs/update.md §3), and at no other ID.

    PYTHONPATH=sim/g031 f6_fit.py SOURCE_DIR BUILD_DIR   (CTest board_stm32g031_f6_fit)
"""
import os
import subprocess
import sys

# The images of the 32 KiB build held to its budget. The application joins
# when it fits (docs/footprint.md "What gives way").
CHECKED = ["km-boot-stm32g031-check"]
MS = 1_000_000


def run(cmd, cwd):
    """Runs cmd, echoes its budget and overflow lines; exits on failure."""
    p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    for line in p.stdout.splitlines():
        if "budget" in line or "overflowed" in line or "error" in line.lower():
            print(line)
    if p.returncode != 0:
        print(p.stdout[-4000:])
        sys.exit("FAIL: %s exited %d" % (" ".join(cmd), p.returncode))


def frame(servo_id, cmd, adr=None):
    """A command frame with its checksum (docs/protocol.md §2)."""
    body = bytes([servo_id, 2 + (adr is not None), cmd]) + (bytes([adr]) if adr is not None else b"")
    return b"\xf9\xff" + body + bytes([~sum(body) & 0xFF])


def ask(m, data):
    """Sends a frame at 115200, returns the bytes answered within 5 ms."""
    m.take_output()
    end = m.send(data, 115200)
    m.run_until(end + 5 * MS)
    return bytes(b for _t, b in m.take_output())


def bootloader_alone(source, images):
    """Update mode of a servo without an application: ID 1 at 115200."""
    import g031_deps  # sim/g031, on PYTHONPATH
    g031_deps.require()
    import argparse
    import vg031
    a = argparse.Namespace(boot=os.path.join(images, "km-boot-stm32g031.elf"), app=None, elf=None,
                           app_elf=None)
    m = vg031.make(a)
    m.run_until(m.now + 20 * MS)
    fails = []
    for sid, want in ((1, bytes.fromhex("F9F5010200FC")), (0, b""), (2, b"")):
        got = ask(m, frame(sid, 0x01))
        print("ping ID %d: %s" % (sid, got.hex(" ") or "no answer"))
        if got != want:
            fails.append("ping ID %d answered %r, expected %r" % (sid, got.hex(" "), want.hex(" ")))
    got = ask(m, frame(1, 0x02, 0x0C))
    print("read 0x0C at ID 1: %s" % got.hex(" "))
    if got[:6] != bytes.fromhex("F9F50107020C"):
        fails.append("0x0C at ID 1 not answered: %r" % got.hex(" "))
    if m.faults or m.resets:
        fails.append("faults %s resets %s" % (m.faults, m.resets))
    return fails


def main():
    source, build = sys.argv[1], sys.argv[2]
    run(["cmake", "--preset", "stm32g031", "-B", build, "-DKM_G031_FLASH_KB=32"], source)
    run(["cmake", "--build", build, "-j2", "--target"] + CHECKED, source)
    images = os.path.join(build, "boards", "stm32g031")
    boot = os.path.getsize(os.path.join(images, "km-boot-stm32g031.bin"))
    print("km-boot-stm32g031.bin: %d B of 4,096" % boot)
    fails = [] if boot <= 4096 else ["bootloader %d B > 4,096" % boot]
    fails += bootloader_alone(source, images)
    for f in fails:
        print("FAIL:", f)
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
