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
import time
import unittest
from types import SimpleNamespace

from kmx import frame as fr
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


class Bootloaders:
    """Servos in update mode on a bus, as the update sees them: 0x78 per
    docs/update.md §4, and deaf while a CRC pass runs: VERIFY reads the
    image back twice, COMMIT's boot check once, at DEAF_S_PER_BYTE a pass
    (the G031 bootloader: 24 instructions a byte at 16 MHz on the virtual
    G031, docs/update.md §4 "After VERIFY and COMMIT"); a frame that
    arrives meanwhile is lost. `drop` = {(ID, sub)}: that servo also loses
    the first broadcast of that sub (a real loss)."""

    DEAF_S_PER_BYTE = 24 / 16e6

    def __init__(self, ids, image, drop=()):
        self.length = struct.unpack_from("<I", image, 8)[0]
        self.blocks = (self.length + kup.BLOCK - 1) // kup.BLOCK
        self.state = dict.fromkeys(ids, 0)
        self.got = {i: set() for i in ids}
        self.deaf_until = dict.fromkeys(ids, 0.0)
        self.erased = dict.fromkeys(ids, False)  # BEGIN erased the old image, no COMMIT since
        self.drop, self.pending, self.lost = set(drop), [], []

    def answer(self, dev_id, body):
        """An answer from dev_id, on the wire once it is done computing."""
        self.pending.append((self.deaf_until[dev_id], fr.Frame(fr.RSP_HEADER, dev_id, body)))

    def busy(self, dev_id, passes):
        self.deaf_until[dev_id] = time.monotonic() + passes * self.length * self.DEAF_S_PER_BYTE

    def run(self, dev_id, data, own):
        """One frame at one servo: its 0x78 state machine (ping: a short answer)."""
        if data[4] == fr.PING:
            self.answer(dev_id, b"\x00")
            return
        sub, st = data[5], self.state[dev_id]
        if sub == kup.ENTER or (sub == kup.BEGIN and st != 0):
            self.state[dev_id], self.got[dev_id] = (1 if sub == kup.ENTER else 2), set()
            self.erased[dev_id] |= sub == kup.BEGIN
        elif sub == kup.WRITE and st == 2:
            self.got[dev_id].add(struct.unpack_from("<H", data, 6)[0])
        elif sub == kup.VERIFY and st == 2 and len(self.got[dev_id]) == self.blocks:
            self.state[dev_id] = 3
            self.busy(dev_id, 2)
        elif sub == kup.COMMIT and st == 3:
            self.state[dev_id], self.erased[dev_id] = 4, False
            self.busy(dev_id, 1)
        elif sub == kup.START and st != 0:
            self.state[dev_id] = 1 if self.erased[dev_id] else 0  # the boot check: a whole image starts
        if own and sub == kup.STATUS:
            bits = bytearray((self.blocks + 7) // 8)
            for b in self.got[dev_id]:
                bits[b // 8] |= 1 << (b % 8)
            self.answer(dev_id, bytes([kup.CMD, sub]) + struct.pack(
                "<BBHHH", self.state[dev_id], 0, self.blocks, len(self.got[dev_id]), 0) + bytes(bits))
        elif own and sub in (kup.BEGIN, kup.WRITE, kup.VERIFY, kup.COMMIT):
            self.answer(dev_id, bytes([kup.CMD, sub, 0]))  # VERIFY, COMMIT: after their CRC passes

    def transact(self, data, answers=0, timeout=None):
        dev_id, now = data[2], time.monotonic()
        for i in self.state if dev_id == kup.BCAST else [dev_id] if dev_id in self.state else []:
            if now < self.deaf_until[i] or (dev_id == kup.BCAST and (i, data[5]) in self.drop):
                self.drop.discard((i, data[5]))
                self.lost.append((i, data[5]))
                continue
            self.run(i, data, dev_id != kup.BCAST)
        return self.listen(timeout, answers) if answers else []

    def listen(self, timeout, n):
        """The answers on the wire within timeout."""
        if self.pending:
            time.sleep(max(0.0, min(timeout or 0.0, min(due for due, _ in self.pending) - time.monotonic())))
        now = time.monotonic()
        out = [f for due, f in self.pending if due <= now]
        self.pending = [(due, f) for due, f in self.pending if due > now]
        return out

    def close(self):
        pass


class VerifyThenCommit(unittest.TestCase):
    """After the broadcast VERIFY the master leaves the servos the time
    their CRC passes take, reads each one's STATUS (VERIFIED), and only
    then broadcasts COMMIT, so a pass with nothing lost sends no VERIFY or
    COMMIT to a servo alone (docs/update.md §4, step 5). A COMMIT sent
    right behind VERIFY lands while every bootloader is still computing."""

    def updater(self, drop=()):
        image = make_image(body_len=32036 - 0x100, model=0x4B4D0002)  # the G031 application's size
        self.bus = Bootloaders([1, 2, 3], image, drop)
        self.lines = []
        up = kup.Updater(self.bus, [1, 2, 3], image, self.lines.append)
        up.baud = 10 ** 12  # no line pacing: the frames follow each other as fast as the master sends them
        return up

    def test_no_frame_lost_and_none_sent_alone(self):
        up = self.updater()
        self.assertEqual(up.one_pass(4), [1, 2, 3])
        self.assertEqual([line for line in self.lines if "missed" in line], [])
        self.assertEqual(self.bus.lost, [])
        self.assertEqual(up.alone, dict.fromkeys(kup.ALONE, 0))
        self.assertEqual(self.bus.state, {1: 0, 2: 0, 3: 0})  # started

    def test_a_lost_verify_or_commit_is_sent_to_that_servo_alone(self):
        up = self.updater(drop={(2, kup.VERIFY), (3, kup.COMMIT)})
        self.assertEqual(up.one_pass(4), [1, 2, 3])
        self.assertEqual([line for line in self.lines if "missed" in line],
                         ["  ID 2 missed VERIFY: sent to it alone", "  ID 3 missed COMMIT: sent to it alone"])
        self.assertEqual(self.bus.lost, [(2, kup.VERIFY), (3, kup.COMMIT)])
        self.assertEqual(up.alone, dict(dict.fromkeys(kup.ALONE, 0), VERIFY=1, COMMIT=1))
        self.assertEqual(self.bus.state, {1: 0, 2: 0, 3: 0})

    def test_rescue_waits_for_verify_before_commit(self):
        up = self.updater()
        self.bus.state = {1: 0}
        up.rescue_pass(1)
        self.assertEqual(self.bus.lost, [])
        self.assertEqual(self.bus.state, {1: 0})  # committed, then START ran the new image


if __name__ == "__main__":
    unittest.main()
