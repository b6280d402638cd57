# SPDX-License-Identifier: Apache-2.0
"""Figures measured on the virtual G031 running the shipped images, for
docs/figures.md (tests/bench/m0/figures.py) and the g031 tests that check
them (tests/g031/test_vg031_flash.py). Virtual time only: the same images
give the same figures on any host.

    flash_op_rows(IMAGES) -> [(flash operation, bytes lost, answer delay us or None)]
    markdown(IMAGES)      -> the section's lines
    stack_high_water(IMAGES) -> (bytes of the stack used, bytes reserved)

IMAGES: the stm32g031 preset's boards/stm32g031 output directory."""
import argparse
import os

import vg031

MS = 1_000_000
BAUD = 115200   # a fresh servo's baud (docs/protocol.md §1)
PAINT = 0x5AFE57AC   # boards/stm32g031/fault.c paints the stack with it at boot
RAM = 0x20000000


def frame(servo_id, cmd, adr=None, params=b""):
    """A command frame with its checksum (docs/protocol.md §2)."""
    body = bytes([servo_id, 2 + len(params) + (adr is not None), cmd])
    body += (bytes([adr]) if adr is not None else b"") + params
    return b"\xf9\xff" + body + bytes([~sum(body) & 0xFF])


def app_machine(images):
    """The bootloader and the application's update image on a blank store;
    (machine, address of km_app_poll)."""
    a = argparse.Namespace(boot=os.path.join(images, "km-boot-stm32g031.elf"),
                           app=os.path.join(images, "km-servo-app-stm32g031.kmfw"), elf=None,
                           app_elf=os.path.join(images, "km-servo-app-stm32g031.elf"))
    poll = vg031.symbol(a.app_elf, "km_app_poll")
    return vg031.make(a, watch=[poll]), poll


def ping(m, servo_id, start):
    """A ping on the wire from `start`: (bytes USART1 lost to overruns,
    µs from its last stop bit to the answer's first start bit or None)."""
    lost = m.usart1.overruns
    m.take_output()
    end = m.send(frame(servo_id, 0x01), BAUD, start=start)
    m.run_until(end + 150 * MS)
    out = m.take_output()
    return m.usart1.overruns - lost, ((out[0][0] - end) / 1000 if len(out) == 6 else None)


def flash_op_rows(images):
    """A ping sent into each kind of flash operation the application
    starts: the first page erase of the idle-time format of a blank store
    (docs/store.md "Preparing in idle time"), then with the bus quiet, then
    into the double-word programs of a commit (ID 0 -> 7, persisted)."""
    m, poll = app_machine(images)
    if not m.run_until(m.now + 300 * MS, stop=lambda: any(k == "erase" for _t, k, _a in m.flashc.ops)):
        raise RuntimeError("no idle-time erase within 300 ms of power-on")
    erase = ("page erase (idle-time format, 22 ms)",) + ping(m, 0, m.now)
    m.run_until(m.now + 300 * MS)   # the format ends
    quiet = ("none (quiet bus)",) + ping(m, 0, m.now)
    write_end = m.send(frame(0, 0x03, 0x0F, b"\x07"), BAUD)
    ops = len(m.flashc.ops)
    lost, delay = ping(m, 7, write_end)
    progs = sum(1 for _t, k, _a in m.flashc.ops[ops:] if k == "prog")
    return [quiet, erase, ("double-word programs of a commit (%d x 85 us)" % progs, lost, delay)]


def markdown(images):
    """The docs/figures.md section: the rows as a table, with the method."""
    out = ["## A ping during flash work (virtual G031, boot + application images)", "",
           "A ping (6 bytes at 115200 baud) sent into each kind of flash operation;"
           " bytes USART1 lost to overruns and the answer's start after the ping's"
           " last stop bit, in virtual time (sim/g031/g031_figures.py; CTest"
           " g031_ping_during_flash_operations checks them).", "",
           "| flash operation under way | bytes lost | answer after the stop bit |", "|---|---|---|"]
    for what, lost, delay in flash_op_rows(images):
        out.append("| %s | %d of 6 | %s |" % (what, lost, "none" if delay is None else "%.1f us" % delay))
    return out + [""]


def stack_high_water(images):
    """The application's stack high-water mark after the traffic of
    tests/g031/test_vg031_flash.py (a ping, the idle-time format of a blank
    store, a persisted setting, a ping 2.5 ms after it): the deepest painted
    word overwritten, as (bytes used below _estack, the reserve above the
    guard band)."""
    m, poll = app_machine(images)
    if not m.run_until(m.now + 100 * MS, stop=lambda: bool(m.watches[poll])):
        raise RuntimeError("the application's main loop did not start within 100 ms")
    m.run_until(m.now + 2 * MS)
    ping(m, 0, m.now)
    m.run_until(m.now + 300 * MS)   # bus silent: the blank store is formatted
    write_end = m.send(frame(0, 0x03, 0x0F, b"\x07"), BAUD)
    ping(m, 7, write_end + 2.5 * MS)
    return stack_use(m, os.path.join(images, "km-servo-app-stm32g031.elf"))


def stack_use(m, elf):
    """The stack m's image `elf` has used so far: the deepest painted word
    overwritten, as (bytes used below _estack, the reserve above the guard
    band)."""
    top = vg031.symbol(elf, "_estack") - RAM
    limit = vg031.symbol(elf, "__stack_limit") - RAM
    guard_end = vg031.symbol(elf, "__stack_guard_end") - RAM
    ram = bytes(m.uc.mem_read(RAM, top))
    low = next(a for a in range(limit, top, 4) if int.from_bytes(ram[a:a + 4], "little") != PAINT)
    return top - low, top - guard_end
