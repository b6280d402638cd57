# SPDX-License-Identifier: Apache-2.0
"""tools/servo-update's checks before it touches a servo (issue 18 item 6):
every bad input (image missing or unreadable, not an image, damaged; --ids
1,x and other bad ID lists; a bad bus spec; neither --ids nor --rescue) is
one line and status 2, never a traceback; servos without a bootloader
(host-sim: 0x0C's bootloader byte 0, docs/update.md §10) and an ID that
does not answer are refused, naming the IDs, before any frame that changes
a servo: afterwards every servo still runs its application and its status
is 0 (an ENTER refused by an application sets bit 5, 0x20). Ctrl-C in the
middle of an update on QEMU bootloaders, and the command it prints that
finishes the job: tests/tools/servo_update_qemu.py (CTest
update_qemu_interrupt). About 5 s."""
import os
import unittest

from test_kmx import REPO  # noqa: E402
from update_tool_rig import AppServos, ImageDir, make_image, run_tool  # noqa: E402

UPDATE = os.path.join(REPO, "tools", "servo-update")


def run_update(*args):
    """tools/servo-update ARGS as a process; a traceback fails the test."""
    return run_tool(UPDATE, *args)


class BadInput(ImageDir, unittest.TestCase):
    """No servo is needed: each is refused before the bus is opened (the bus
    named is one where nothing listens)."""

    def refused(self, message, *args):
        r = run_update(*args)
        self.assertEqual((r.returncode, r.stdout, r.stderr), (2, "", "servo-update: %s\n" % message), args)

    def test_images(self):
        bus = ("--bus", "tcp:127.0.0.1:9", "--ids", "1")
        missing = os.path.join(self.dir.name, "missing.kmfw")
        self.refused("cannot read the image %s: No such file or directory" % missing, *bus, missing)
        self.refused("cannot read the image %s: Is a directory" % self.dir.name, *bus, self.dir.name)
        text = self.file("notes.txt", b"not an image\n" * 40)
        self.refused("%s is not an update image (tools/gen/make-image)" % text, *bus, text)
        image = bytearray(make_image())
        image[12] ^= 1
        bad = self.file("header.kmfw", bytes(image))
        self.refused("%s: header CRC does not match" % bad, *bus, bad)
        short = self.file("short.kmfw", make_image()[:-100])
        self.refused("%s: the header says 1280 bytes, the file has 1180" % short, *bus, short)
        image = bytearray(make_image())
        image[0x200] ^= 0x55
        bad = self.file("body.kmfw", bytes(image))
        self.refused("%s: body CRC does not match (a damaged image)" % bad, *bus, bad)

    def test_command_line(self):
        bus = ("--bus", "tcp:127.0.0.1:9")
        for ids, why in (("1,x", "'x' is not a servo ID (0..250)"), ("1,,2", "'' is not a servo ID (0..250)"),
                         ("1,300", "servo ID 300 is outside 0..250"), ("3,3", "ID 3 is listed twice"),
                         ("-1", "servo ID -1 is outside 0..250")):
            with self.subTest(ids=ids):
                self.refused("argument --ids: %s (servo-update --help)" % why, *bus, "--ids=" + ids, self.good)
        self.refused("give --ids (the servos to update) or --rescue (one servo alone on the bus)", *bus, self.good)
        self.refused("give --ids (the servos to update) or --rescue (one servo alone on the bus), not both",
                     *bus, "--ids", "1", "--rescue", self.good)
        self.refused("argument --rounds: '0' is not a whole number of at least 1 (servo-update --help)",
                     *bus, "--ids", "1", "--rounds", "0", self.good)
        self.refused("the following arguments are required: --bus (servo-update --help)", "--ids", "1", self.good)
        self.refused("bus 'tcp:7000': tcp wants HOST:PORT, e.g. tcp:127.0.0.1:7000",
                     "--bus", "tcp:7000", "--ids", "1", self.good)
        r = run_update("--bus", "tcp:127.0.0.1:9", "--ids", "1", self.good)
        self.assertEqual(r.returncode, 2)
        self.assertRegex(r.stderr, r"^servo-update: tcp:127.0.0.1:9: connection refused .*\n$")


class NothingTouched(AppServos, unittest.TestCase):
    """Two host-sim servos: applications without a bootloader."""

    def test_no_bootloader(self):
        r = run_update("--bus", self.wire.spec, "--ids", "1,2", self.image)
        self.assertEqual((r.returncode, r.stderr),
                         (1, "servo-update: refused, nothing sent to any servo: ID 1, 2 have no bootloader "
                             "(0x0C 0x00100100, 0x00100100, bootloader byte 0; docs/update.md §10): flash one with "
                             "a programmer first\n"))
        self.untouched()

    def test_absent_id(self):
        r = run_update("--bus", self.wire.spec, "--ids", "2,7", self.image)
        self.assertEqual(r.returncode, 1)
        self.assertEqual(r.stderr, "servo-update: refused, nothing sent to any servo: ID 7 does not answer on %s "
                                   "(kmx --bus %s scan lists the IDs there); ID 2 has no bootloader (0x0C "
                                   "0x00100100, bootloader byte 0; docs/update.md §10): flash one with a "
                                   "programmer first\n" % (self.wire.spec, self.wire.spec))
        self.untouched()


if __name__ == "__main__":
    unittest.main()
