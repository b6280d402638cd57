#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The 32 KiB STM32G031F6 build (docs/footprint.md "STM32G031F6") keeps
fitting: configures `cmake --preset stm32g031 -DKM_G031_FLASH_KB=32` in its
own build directory, builds the images with their image-check, which in
that build enforces the budget (--enforce-budget: bootloader <= 4,096 B,
the application + its header <= 22,528 B, what the bootloader and the
store leave, an image without bootloader <= 26,624 B beside the store,
RAM <= 6 KiB), and runs them on the virtual G031 (sim/g031): the
bootloader alone, with no application and no store reader, answers at ID
1, 115200 (docs/update.md §3), and at no other ID; the bootloader with
the application's update image in its region starts the application,
which answers at its default ID 0 (update mode's ID 1 stays silent); the
servo image without
bootloader (the 32 KiB build's compact parser, control and run-time
routines) answers a ping at its default ID 0 after the longest frame to
another servo, and reports a checksum-failed frame to it once (§2, §4), on
the RAM vectors its reset handler built from its 28-byte flash table.

    PYTHONPATH=sim/g031 f6_fit.py SOURCE_DIR BUILD_DIR   (CTest board_stm32g031_f6_fit)
"""
import os
import subprocess
import sys

# The images of the 32 KiB build held to its budget: the bootloader, the
# image without bootloader and, since it fits (docs/footprint.md
# "STM32G031F6"), the application in the bootloader's layout.
CHECKED = ["km-boot-stm32g031-check", "km-servo-stm32g031-check", "km-servo-app-stm32g031-check",
           "km-servo-app-stm32g031-kmfw"]  # the update image: what the bootloader starts
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


def boot_and_application(images):
    """The bootloader with the 32 KiB application in its region: the application answers at ID 0."""
    import g031_deps  # sim/g031, on PYTHONPATH
    g031_deps.require()
    import argparse
    import vg031
    a = argparse.Namespace(boot=os.path.join(images, "km-boot-stm32g031.elf"),
                           app=os.path.join(images, "km-servo-app-stm32g031.kmfw"), elf=None,
                           app_elf=os.path.join(images, "km-servo-app-stm32g031.elf"))
    start = vg031.symbol(a.app_elf, "Reset_Handler")
    m = vg031.make(a, watch=[start])
    m.run_until(m.now + 300 * MS)  # the boot check: the CRC of the whole application
    started = m.watches[start]
    print("bootloader + application: application started at %s" %
          ("%.1f ms" % (started[0][0] / MS) if started else "no time (never)"))
    fails = [] if started else ["bootloader + application: the application never started"]
    for sid, want in ((0, bytes.fromhex("F9F5000200FD")), (1, b"")):
        got = ask(m, frame(sid, 0x01))
        print("bootloader + application, ping ID %d: %s" % (sid, got.hex(" ") or "no answer"))
        if got != want:
            fails.append("bootloader + application, ping ID %d answered %r, expected %r"
                         % (sid, got.hex(" "), want.hex(" ")))
    if m.faults or m.resets:
        fails.append("bootloader + application: faults %s resets %s" % (m.faults, m.resets))
    return fails


def servo_alone(images):
    """The stand-alone 32 KiB servo image: pings at ID 0 through a long frame and a bad checksum."""
    import g031_deps  # sim/g031, on PYTHONPATH
    g031_deps.require()
    import argparse
    import vg031
    a = argparse.Namespace(boot=None, app=None, elf=os.path.join(images, "km-servo-stm32g031.elf"),
                           app_elf=None)
    m = vg031.make(a)
    m.run_until(m.now + 50 * MS)
    # The longest frame (length 252: 256 bytes) to servo 7, a 0x03 write, then a ping to ID 0.
    long_body = bytes([7, 252, 0x03]) + bytes(range(250))
    long_frame = b"\xf9\xff" + long_body + bytes([~sum(long_body) & 0xFF])
    bad = bytearray(frame(0, 0x01))
    bad[-1] ^= 0xFF
    ok, exception = bytes.fromhex("F9F5000200FD"), bytes.fromhex("F9F5000220DD")
    fails = []
    for what, data, want in (("ping", frame(0, 0x01), ok), ("longest frame, ping", long_frame + frame(0, 0x01), ok),
                             ("bad checksum", bytes(bad), b""), ("ping after it", frame(0, 0x01), exception),
                             ("ping again", frame(0, 0x01), ok)):
        got = ask(m, data)
        print("servo image, %s: %s" % (what, got.hex(" ") or "no answer"))
        if got != want:
            fails.append("servo image, %s: answered %r, expected %r" % (what, got.hex(" "), want.hex(" ")))
    if m.faults or m.resets:
        fails.append("servo image: faults %s resets %s" % (m.faults, m.resets))
    return fails + vector_tables(m, a.elf)


def symbols(elf_path, *names):
    """(address with its Thumb bit, size) of each named symbol of an ELF."""
    from elftools.elf.elffile import ELFFile
    found = {}
    with open(elf_path, "rb") as f:
        for sym in ELFFile(f).get_section_by_name(".symtab").iter_symbols():
            if sym.name in names and sym.name not in found:
                found[sym.name] = (sym["st_value"], sym["st_size"])
    return [found[n] for n in names]


def vector_tables(m, elf):
    """The 32 KiB build's flash vector table holds 7 words (SP, reset, NMI,
    HardFault, SysTick, TIM2, USART1: startup.c KM_G031_SHORT_VECTORS) and
    the reset handler builds from it the 48 RAM vectors: the handlers at
    SysTick (15), TIM2 (16 + 15) and USART1 (16 + 27), NMI, and the fault
    path (HardFault_Handler, where the default handler branches) at every
    other vector (docs/footprint.md "STM32G031F6")."""
    (table, size), (ram, _), (sp, _), (reset, _), (nmi, _), (hard, _), (tick, _), (tim2, _), (usart1, _) = \
        symbols(elf, "s_vectors", "__ram_vectors", "_estack", "Reset_Handler", "NMI_Handler", "HardFault_Handler",
                "SysTick_Handler", "TIM2_IRQHandler", "USART1_IRQHandler")
    want = [hard] * 48
    want[0:3] = [sp, reset, nmi]
    want[15], want[16 + 15], want[16 + 27] = tick, tim2, usart1
    got = [int.from_bytes(m.uc.mem_read(ram + 4 * k, 4), "little") for k in range(48)]
    print("servo image: flash vector table %d B at %#x; RAM table at %#x %s" % (size, table, ram,
          "as expected" if got == want else "DIFFERS"))
    fails = [] if size == 28 else ["flash vector table %d B, expected 28" % size]
    if got != want:
        fails.append("RAM vectors %s, expected %s" % ([hex(w) for w in got], [hex(w) for w in want]))
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
    fails += boot_and_application(images)
    fails += servo_alone(images)
    for f in fails:
        print("FAIL:", f)
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
