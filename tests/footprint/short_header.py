#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The 32-byte application header (board.cmake KM_G031_SHORT_HEADER, on in
the 32 KiB build; docs/update.md §2, docs/footprint.md "STM32G031F6"),
end to end on the virtual G031. Configures the 64 KiB layout with
-DKM_G031_SHORT_HEADER=ON in its own build directory (the short header
alone, on the 64 KiB layout the stm32g031 preset's 256-byte format is
built for, so check 3 can swap the two; board_stm32g031_f6_fit starts
the 32 KiB build's short-header application through its bootloader),
builds the bootloader and the application's update image, and checks:
  1. the image: header field `vectors` 0x20, length 32 + the .bin, the
     application's vector table linked at the region's start + 0x20;
  2. that bootloader starts that image: the application reaches its main
     loop with no fault or reset, the bootloader wrote no VTOR (the table
     at +0x20 is not 256-aligned; docs/update.md §2), the only VTOR write
     is the application's own, its RAM copy of the table;
  3. the two formats do not mix: the same image with `vectors` 0x100 (its
     header CRC redone) is refused by this bootloader, and this image by a
     bootloader of the 256-byte format (BUILD_256, the stm32g031 preset's):
     update mode answers a ping, the application never runs.

    PYTHONPATH=sim/g031 short_header.py SOURCE_DIR BUILD_DIR BUILD_256
    (CTest board_stm32g031_short_header)
"""
import argparse
import os
import struct
import subprocess
import sys
import tempfile
import zlib

MS = 1_000_000
REGION = 0x08002000  # the 64 KiB layout's application region (boot/boot_layout.h)


def run(cmd, cwd):
    """Runs cmd; exits with its output's tail on failure."""
    p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if p.returncode != 0:
        print(p.stdout[-4000:])
        sys.exit("FAIL: %s exited %d" % (" ".join(cmd), p.returncode))


def ping(m, servo_id=0):
    """A ping at 115200 (docs/protocol.md §2); the bytes answered within 5 ms."""
    body = bytes([servo_id, 2, 0x01])
    m.take_output()
    end = m.send(b"\xf9\xff" + body + bytes([~sum(body) & 0xFF]), 115200)
    m.run_until(end + 5 * MS)
    return bytes(b for _t, b in m.take_output())


def machine(boot, kmfw, app_elf):
    """A virtual G031 with boot and kmfw in flash, VTOR writes recorded:
    (machine, km_app_poll's address, [VTOR values written])."""
    import vg031
    poll = vg031.symbol(app_elf, "km_app_poll")
    m = vg031.make(argparse.Namespace(boot=boot, app=kmfw, elf=None, app_elf=app_elf), watch=[poll])
    writes = []
    scs_write = m.scs.write

    def record(off, val, now):
        if off == 0xD08:
            writes.append(val)
        scs_write(off, val, now)
    m.scs.write = record
    return m, poll, writes


def check_image(kmfw, binary, app_elf):
    """Check 1: the header and the link address of the vector table."""
    import vg031
    with open(kmfw, "rb") as f:
        img = f.read()
    magic, _model, length, _version, vectors, base = struct.unpack_from("<IIIIII", img)
    table = vg031.symbol(app_elf, "s_vectors")
    print("image: vectors %#x, length %d (.bin %d), base %#x, s_vectors at %#x"
          % (vectors, length, os.path.getsize(binary), base, table))
    fails = []
    if magic != 0x57464D4B or vectors != 0x20 or length != 32 + os.path.getsize(binary):
        fails.append("header: vectors %#x length %d, expected 0x20 and 32 + the .bin" % (vectors, length))
    if base != REGION or table != REGION + 0x20:
        fails.append("vector table at %#x, base %#x: expected the region + 0x20" % (table, base))
    return fails


def check_start(boot, kmfw, app_elf):
    """Check 2: the bootloader starts the image; VTOR is the application's."""
    import vg031
    m, poll, writes = machine(boot, kmfw, app_elf)
    m.run_until(m.now + 200 * MS, stop=lambda: bool(m.watches[poll]))
    ram_vectors = vg031.symbol(app_elf, "__ram_vectors")
    print("short header: main loop %s, VTOR writes %s (RAM table %#x)"
          % ("reached" if m.watches[poll] else "NOT reached", [hex(v) for v in writes], ram_vectors))
    fails = []
    if not m.watches[poll] or m.faults or m.resets:
        fails.append("application not started: faults %s resets %s" % (m.faults, m.resets))
    if writes != [ram_vectors]:
        fails.append("VTOR writes %s, expected only the application's %#x" % ([hex(v) for v in writes], ram_vectors))
    m.run_until(m.now + 2 * MS)  # before the store's first format (its erases hold a ping up)
    got = ping(m)
    print("short header: application ping %s" % got.hex(" "))
    if got[:3] != bytes.fromhex("F9F500"):
        fails.append("the application does not answer a ping at ID 0: %r" % got.hex(" "))
    return fails


def refused(what, boot, kmfw, app_elf):
    """Check 3: an image of the other format stays in the region unstarted;
    update mode answers a ping at ID 0 (a fresh store: docs/update.md §3)."""
    m, poll, _writes = machine(boot, kmfw, app_elf)
    m.run_until(m.now + 200 * MS, stop=lambda: bool(m.watches[poll]))
    got = ping(m)
    print("%s: main loop %s, update mode ping %s" % (what, "reached" if m.watches[poll] else "not reached",
                                                      got.hex(" ") or "no answer"))
    if m.watches[poll] or got[:3] != bytes.fromhex("F9F500") or m.faults:
        return ["%s: started or silent (faults %s)" % (what, m.faults)]
    return []


def as_256(kmfw, out):
    """The image with its header's vectors field 0x100, header CRC redone."""
    with open(kmfw, "rb") as f:
        img = bytearray(f.read())
    struct.pack_into("<I", img, 16, 0x100)
    struct.pack_into("<I", img, 28, zlib.crc32(bytes(img[:28])) & 0xFFFFFFFF)
    with open(out, "wb") as f:
        f.write(img)


def main():
    source, build, build_256 = sys.argv[1], sys.argv[2], sys.argv[3]
    import g031_deps  # sim/g031, on PYTHONPATH
    g031_deps.require()
    run(["cmake", "--preset", "stm32g031", "-B", build, "-DKM_G031_SHORT_HEADER=ON"], source)
    run(["cmake", "--build", build, "-j2", "--target", "km-boot-stm32g031", "km-servo-app-stm32g031-kmfw"], source)
    images = os.path.join(build, "boards", "stm32g031")
    boot = os.path.join(images, "km-boot-stm32g031.elf")
    kmfw = os.path.join(images, "km-servo-app-stm32g031.kmfw")
    app_elf = os.path.join(images, "km-servo-app-stm32g031.elf")
    fails = check_image(kmfw, os.path.join(images, "km-servo-app-stm32g031.bin"), app_elf)
    fails += check_start(boot, kmfw, app_elf)
    with tempfile.TemporaryDirectory() as tmp:
        other = os.path.join(tmp, "vectors-0x100.kmfw")
        as_256(kmfw, other)
        fails += refused("short-header bootloader, image saying vectors 0x100", boot, other, app_elf)
    boot_256 = os.path.join(build_256, "boards", "stm32g031", "km-boot-stm32g031.elf")
    if not os.path.isfile(boot_256):
        fails.append("missing %s: cmake --preset stm32g031 && cmake --build --preset stm32g031" % boot_256)
    else:
        fails += refused("256-byte-header bootloader, short-header image", boot_256, kmfw, app_elf)
    for f in fails:
        print("FAIL:", f)
    if not fails:
        print("all checks passed")
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
