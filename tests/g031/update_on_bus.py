#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Firmware update end to end on three virtual STM32G031s (docs/update.md):
the shipped km-boot-stm32g031.elf with km-servo-app-stm32g031.kmfw in its
application region, on servo-bus --backend g031, driven by
tools/servo-update exactly as on QEMU (tests/qemu/update_e2e.py):
  1. every servo answers a ping and 0x0C (the version of the image);
  2. an image for another model (the stm32g031 image with its header's
     model changed, header CRC redone) is refused by all three, nothing
     erased: after START they run the old image again;
  3. the second application build (km-servo-app-v2-stm32g031.kmfw, software
     version 0x0102: the application answers 0x0C from its own code, so
     only a different build shows the update landed) to all three in one
     broadcast pass, through the real bootloader's erase and program: 0x0C
     gives 0x10100102, and no ENTER, BEGIN, VERIFY or COMMIT had to be sent
     to a servo alone (the master waits for VERIFY's CRC passes before the
     broadcast COMMIT, docs/update.md §4 "After VERIFY and COMMIT");
  4. back to the shipped version with RESTARTS restart frames and RESETS
     NRST resets (the bus's monitor sockets, as QEMU's system_reset) at
     random points of the pass; the update completes on every servo.
Prints "all checks passed" at the end; exit 1 on any failure.
    update_on_bus.py [--restarts N] [--resets N] [--seed S] [--build-stm32 DIR]
"""
import argparse
import os
import struct
import subprocess
import sys
import tempfile
import time
import zlib

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
import vclock  # noqa: E402  (sim/g031, on PYTHONPATH)
import g031_servo_bus  # noqa: E402  (sim/g031)
from kmx.bus import Bus  # noqa: E402
from kmx import frame as fr  # noqa: E402

HEADER = "<IIIIIIII"   # magic, model, length, version, vectors, base, body CRC, header CRC (docs/update.md §2)


def variant(image, model_xor):
    """The image with its header's model changed and the header CRC redone;
    the body and its CRC stay the shipped ones."""
    f = list(struct.unpack_from(HEADER, image))
    f[1] ^= model_xor
    head = struct.pack("<IIIIIII", *f[:7])
    head += struct.pack("<I", zlib.crc32(head) & 0xFFFFFFFF)
    return head + image[32:]


def versions(spec, ids):
    """0x0C of each servo (None when it does not answer)."""
    with Bus(spec, timeout=0.5) as bus:
        out = {}
        for i in ids:
            try:
                out[i] = int.from_bytes(bus.read(i, 0x0C), "little")
            except Exception:  # noqa: BLE001  (a servo that does not answer)
                out[i] = None
        return out


def run_update(update, path, extra=()):
    """tools/servo-update on the bus's virtual time (sim/g031/vclock.py) with
    its output echoed; its exit status and output."""
    r = subprocess.run(update + list(extra) + [path], capture_output=True, text=True)
    print(r.stdout.strip(), flush=True)
    if r.stderr.strip():
        print(r.stderr.strip(), flush=True)
    return r.returncode, r.stdout


def checks(spec, mon, tmp, image, image_v2, a):
    """The four steps; the failures."""
    ids, failures = (1, 2, 3), []
    update = [sys.executable, vclock.__file__, os.path.join(tmp, "clock"), os.path.join(REPO, "tools/servo-update"),
              "--bus", spec, "--ids", "1,2,3"]
    v = versions(spec, ids)
    print("0x0C at start:", {i: None if x is None else "0x%08X" % x for i, x in v.items()}, flush=True)
    if any(x is None for x in v.values()):
        failures.append("1: a servo does not answer 0x0C")
    paths = {}
    for name, data in (("other", variant(image, 0x00FF0000)), ("next", image_v2), ("shipped", image)):
        paths[name] = os.path.join(tmp, name + ".kmfw")
        with open(paths[name], "wb") as f:
            f.write(data)
    rc, out = run_update(update, paths["other"], ["--attempts", "1"])
    if rc == 0 or out.count("wrong model") < 3:
        failures.append("2: the other model's image was not refused by all three")
    with Bus(spec, timeout=0.3) as bus:
        bus.send_bytes(fr.encode_command(0xFE, 0x78, 0x07, bytes([0xE1, 0xE2, 0xE3, 0xE4])))
    time.sleep(2.0)
    if versions(spec, ids) != v:
        failures.append("2: after the refusal the servos do not run the old image")
    rc, out = run_update(update, paths["next"])
    got = versions(spec, ids)
    want = struct.unpack_from(HEADER, image_v2)[3] | 0x10000000  # the bootloader's byte 0x10 on top
    if rc != 0 or any(x != want for x in got.values()):
        failures.append("3: v2 (0x%08X) not on all three: %r" % (want, got))
    if "sent alone after a lost broadcast: ENTER 0, BEGIN 0, VERIFY 0, COMMIT 0," not in out:
        failures.append("3: the pass sent a step to a servo alone (a broadcast lost, e.g. a COMMIT "
                        "while the bootloaders still computed VERIFY's CRC, docs/update.md §4)")
    rc, out = run_update(update, paths["shipped"], ["--restarts", str(a.restarts), "--seed", str(a.seed),
                                                    "--resets", str(a.resets), "--monitor-dir", mon])
    got = versions(spec, ids)
    if rc != 0 or got != v:
        failures.append("4: back to the shipped image with resets did not complete: %r" % got)
    if "%d restarts injected, %d resets injected, 0 times" % (a.restarts, a.resets) not in out:
        failures.append("4: not every restart or reset injected, or a servo unreachable after one")
    return failures


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--restarts", type=int, default=2)
    ap.add_argument("--resets", type=int, default=2)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--build-stm32", default=os.path.join(REPO, "build/stm32g031"))
    a = ap.parse_args()
    images = []
    for name in ("km-servo-app-stm32g031.kmfw", "km-servo-app-v2-stm32g031.kmfw"):
        kmfw = os.path.join(a.build_stm32, "boards/stm32g031", name)
        if not os.path.isfile(kmfw):
            print("missing %s: cmake --preset stm32g031 && cmake --build --preset stm32g031" % kmfw)
            return 1
        with open(kmfw, "rb") as f:
            images.append(f.read())
    image, image_v2 = images
    tmp = tempfile.TemporaryDirectory(prefix="g031-update-")
    t0 = time.monotonic()
    try:
        with g031_servo_bus.servo_bus((1, 2, 3), ["--build-dir", a.build_stm32, "--monitor-dir", tmp.name,
                                                  "--timeout", "30"], tmp.name) as (spec, clock):
            print("bus: %s, up in %.1f s" % (spec, vclock.real_monotonic() - t0), flush=True)
            v0 = clock.ns()
            failures = checks(spec, tmp.name, tmp.name, image, image_v2, a)
            print("virtual time %.1f s" % ((clock.ns() - v0) / 1e9))
    finally:
        tmp.cleanup()
    print("run time %.1f s real" % (vclock.real_monotonic() - t0))
    for f in failures:
        print("FAIL", f)
    if failures:
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
