#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Flash work and the bus on the virtual STM32G031 (sim/g031) running the
shipped images (issue 21 goals 5 and 6; docs/store.md "Preparing in idle
time"): a blank store is formatted while the bus is silent, so the first
saved setting is answered without an erase in its way and a ping 2.5 ms
after it is answered on time; and the stack's measured high-water mark
after that traffic (the stack is painted at boot, README of the board).

    test_vg031_flash.py BUILD_DIR/boards/stm32g031
"""
import argparse
import os
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
import g031_deps  # noqa: E402
g031_deps.require()
import vg031  # noqa: E402
import g031_figures  # noqa: E402

IMAGES = None
BAUD = 115200        # a fresh servo's baud (docs/protocol.md §1)
MS = 1_000_000


def frame(servo_id, cmd, adr=None, params=b""):
    """A command frame with its checksum (docs/protocol.md §2)."""
    body = bytes([servo_id, 2 + len(params) + (adr is not None), cmd])
    body += (bytes([adr]) if adr is not None else b"") + params
    return b"\xf9\xff" + body + bytes([~sum(body) & 0xFF])


def app_machine():
    """The bootloader and the application's update image, blank store."""
    a = argparse.Namespace(boot=os.path.join(IMAGES, "km-boot-stm32g031.elf"),
                           app=os.path.join(IMAGES, "km-servo-app-stm32g031.kmfw"), elf=None,
                           app_elf=os.path.join(IMAGES, "km-servo-app-stm32g031.elf"))
    poll = vg031.symbol(a.app_elf, "km_app_poll")
    return vg031.make(a, watch=[poll]), poll, a.app_elf


def ping_delay_us(m, servo_id, start):
    """Sends a ping at `start`; µs from its last stop bit to the answer's first start bit."""
    m.take_output()
    end = m.send(frame(servo_id, 0x01), BAUD, start=start)
    m.run_until(end + 150 * MS)
    out = m.take_output()
    return ((out[0][0] - end) / 1000 if out else None), len(out)


class Flash(unittest.TestCase):
    def test_first_saved_setting_after_idle_format_ping_on_time(self):
        m, poll, elf = app_machine()
        self.assertTrue(m.run_until(m.now + 100 * MS, stop=lambda: bool(m.watches[poll])))
        m.run_until(m.now + 2 * MS)
        quiet, n = ping_delay_us(m, 0, m.now)
        self.assertEqual(n, 6)
        m.run_until(m.now + 300 * MS)  # bus silent: the blank store is formatted (3 x 22 ms)
        write_end = m.send(frame(0, 0x03, 0x0F, b"\x07"), BAUD)  # ID 0 -> 7, persisted
        late, n = ping_delay_us(m, 7, write_end + 2.5 * MS)
        print("ping answered %.1f us after its stop bit in a quiet bus, %.1f us 2.5 ms after the "
              "first saved setting" % (quiet, late))
        self.assertEqual(n, 6, "no answer from ID 7")
        self.assertLessEqual(late, quiet + 100)
        self.assertEqual(m.faults, [])
        used, reserve = g031_figures.stack_use(m, elf)  # the deepest painted word overwritten
        print("stack high-water %d B of the %d B reserve (%.0f %%)" % (used, reserve, 100.0 * used / reserve))
        self.assertLessEqual(used, reserve * 80 // 100)

    def test_ping_during_each_kind_of_flash_operation(self):
        """A ping sent into each kind of flash operation (sim/g031/g031_figures.py,
        the figures of docs/figures.md): no byte lost (USART1's handler and
        the vector table are in RAM, RM0444 §33.5.6 overruns counted); the
        answer on time except through an erase, which stalls the main loop
        in flash (§3.3.7) to its end."""
        rows = {what.split(" (")[0]: (lost, delay) for what, lost, delay in g031_figures.flash_op_rows(IMAGES)}
        for what, (lost, delay) in rows.items():
            print("flash op %-36s bytes lost %d of 6, answer %.1f us" % (what, lost, delay))
        quiet = rows["none"][1]
        self.assertEqual([lost for lost, _d in rows.values()], [0, 0, 0])
        self.assertLessEqual(rows["double-word programs of a commit"][1], quiet + 100)
        self.assertTrue(20_000 <= rows["page erase"][1] <= 23_000, rows["page erase"])

def main():
    global IMAGES
    IMAGES = sys.argv.pop(1)
    unittest.main(verbosity=2)


if __name__ == "__main__":
    main()
