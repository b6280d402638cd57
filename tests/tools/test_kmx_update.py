# SPDX-License-Identifier: Apache-2.0
"""`kmx update` and `kmx trace` (issue 19: servo-update and servo-session
become kmx subcommands, host/kmx/update.py and host/kmx/session.py; the old
names stay as thin wrappers, tests/tools/test_servo_update.py): the update's
one-line refusals (image, command line, bus spec: status 2) and its checks
before touching a servo (an ID that does not answer, no bootloader in 0x0C,
docs/update.md §10: status 1, both servos still run their application);
`kmx trace` prints the session servo-session prints; `kmx --trace` decodes
every answer with register names and units. A servo in update mode, the
Ctrl-C of `kmx update` and the command it prints: tests/tools/
servo_update_qemu.py (CTest update_qemu_interrupt). About 8 s."""
import os
import re
import struct
import unittest
from types import SimpleNamespace

from kmx import update as kup

from test_kmx import REPO, ServoBus
from update_tool_rig import AppServos, ImageDir, make_image, run_tool

KMX = os.path.join(REPO, "tools", "kmx")


def run_kmx(*args):
    """tools/kmx ARGS as a process; a traceback fails the test."""
    return run_tool(KMX, *args)


class UpdateBadInput(ImageDir, unittest.TestCase):
    """Refused before the bus is opened: one line `kmx: ...`, status 2."""

    def refused(self, message, *args):
        r = run_kmx("--bus", "tcp:127.0.0.1:9", "update", *args)
        self.assertEqual((r.returncode, r.stdout, r.stderr), (2, "", "kmx: %s\n" % message), args)

    def test_image_and_ids(self):
        missing = os.path.join(self.dir.name, "missing.kmfw")
        self.refused("cannot read the image %s: No such file or directory" % missing, "--ids", "1", missing)
        image = bytearray(make_image())
        image[0x200] ^= 0x55
        bad = self.file("body.kmfw", bytes(image))
        self.refused("%s: body CRC does not match (a damaged image)" % bad, "--ids", "1", bad)
        self.refused("give --ids (the servos to update) or --rescue (one servo alone on the bus)", self.good)
        self.refused("give --ids (the servos to update) or --rescue (one servo alone on the bus), not both",
                     "--ids", "1", "--rescue", self.good)
        r = run_kmx("--bus", "tcp:127.0.0.1:9", "update", "--ids", "1,x", self.good)
        self.assertEqual(r.returncode, 2)
        self.assertIn("argument --ids: 'x' is not a servo ID (0..250)", r.stderr)

    def test_bus(self):
        r = run_kmx("--bus", "tcp:7000", "update", "--ids", "1", self.good)
        self.assertEqual((r.returncode, r.stderr), (2, "kmx: bus 'tcp:7000': tcp wants HOST:PORT, e.g. "
                                                       "tcp:127.0.0.1:7000\n"))
        r = run_kmx("--bus", "tcp:127.0.0.1:9", "update", "--ids", "1", self.good)
        self.assertEqual(r.returncode, 2)
        self.assertRegex(r.stderr, r"^kmx: tcp:127.0.0.1:9: connection refused .*\n$")

    def test_help_names_update_and_trace(self):
        out = run_kmx("--help").stdout
        self.assertRegex(out, r"\n\s+update\s+firmware update")
        self.assertRegex(out, r"\n\s+trace\s+scan and read every servo")
        self.assertIn("--rescue", run_kmx("update", "--help").stdout)


class UpdateOnHostSim(AppServos, unittest.TestCase):
    """Two host-sim servos: applications without a bootloader (0x0C's
    bootloader byte 0): kmx update refuses them, and an absent ID, naming
    them, before any frame that changes a servo."""

    def test_no_bootloader_and_absent(self):
        r = run_kmx("--bus", self.wire.spec, "update", "--ids", "2,7", self.image)
        self.assertEqual((r.returncode, r.stderr),
                         (1, "kmx: refused, nothing sent to any servo: ID 7 does not answer on %s (kmx --bus %s "
                             "scan lists the IDs there); ID 2 has no bootloader (0x0C 0x00100100, bootloader "
                             "byte 0; docs/update.md §10): flash one with a programmer first\n"
                          % (self.wire.spec, self.wire.spec)))
        self.untouched(update_state=True)

    def test_ping_of_an_application_says_nothing_of_update_mode(self):
        r = run_kmx("--bus", self.wire.spec, "ping", "1")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stdout, r"^ID 1: status 0x00 \(ok\), answered in \d+\.\d ms\n$")


class Trace(unittest.TestCase):
    """kmx trace is servo-session's session; kmx --trace decodes answers."""

    @classmethod
    def setUpClass(cls):
        cls.wire = ServoBus()

    @classmethod
    def tearDownClass(cls):
        cls.wire.close()

    def test_trace_read_only_as_servo_session(self):
        r = run_kmx("--bus", self.wire.spec, "trace")
        self.assertEqual(r.returncode, 0, r.stderr)
        sent = [line.split(" > ")[1].split() for line in r.stdout.splitlines() if " > " in line]
        self.assertTrue(sent)
        self.assertEqual([f for f in sent if len(f) > 4 and f[1] == "FF" and f[4] == "03"], [])
        self.assertIn("-- read only: nothing written, nothing moved", r.stdout)
        for i in (1, 2, 3):
            self.assertRegex(r.stdout, r"< F9 F5 0%d 02 00 ..   id %d status 0x00 ok" % (i, i))
            self.assertIn("id %d voltage (0x4B) = 7.400 V" % i, r.stdout)

    def test_global_trace_decodes(self):
        r = run_kmx("--bus", self.wire.spec, "--trace", "get", "2", "voltage")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout, "voltage (0x4B) = 7.400 V\n")
        self.assertRegex(r.stderr, re.compile(r"^> F9 FF 02 03 02 4B AD$", re.M))
        self.assertRegex(r.stderr, re.compile(r"^< F9 F5 02 05 02 4B E8 1C A7   id 2 voltage \(0x4B\) = 7.400 V$",
                                              re.M))


class LostStart(unittest.TestCase):
    """A broadcast START gets no answer, so a servo that missed it stays
    committed in its bootloader: the updater asks STATUS of each ID and
    sends START to that one alone (docs/update.md §4, step 6)."""

    class Bus:
        """Answers 0x78 STATUS: state 4 (committed) for the IDs in `stuck`
        until a START reaches them alone, else state 0 (application)."""

        def __init__(self, stuck):
            self.stuck, self.sent, self.pending = set(stuck), [], []

        def transact(self, data, answers=0, timeout=None):
            dev_id, sub = data[2], data[5]
            self.sent.append((dev_id, sub))
            if sub == kup.START and dev_id in self.stuck:
                self.stuck.discard(dev_id)
            if sub == kup.STATUS:
                state = 4 if dev_id in self.stuck else 0
                params = struct.pack("<BBHHH", state, 0, 0, 0, 0)
                self.pending.append(SimpleNamespace(id=dev_id, is_status=False, cmd=kup.CMD,
                                                    addr=kup.STATUS, params=params))
            return []

        def listen(self, timeout, n):
            out, self.pending = self.pending, []
            return out

    def test_start_resent_only_to_the_servo_that_missed_it(self):
        bus = self.Bus(stuck=[2])
        lines = []
        up = kup.Updater(bus, [1, 2, 3], make_image(), lines.append)
        up.restart_missed([1, 2, 3])
        self.assertEqual([d for d, sub in bus.sent if sub == kup.START], [2])
        self.assertEqual(lines, ["  ID 2 missed START: sent to it alone"])
        self.assertEqual(bus.stuck, set())


if __name__ == "__main__":
    unittest.main()
