# SPDX-License-Identifier: Apache-2.0
"""One servo per ID (docs/protocol.md §1; §5.1 0x01's random byte; issue 18
item 7): every path that writes an ID (kmx set ID id N, set ID 0x0F N,
set-id, set ID userdata_reset 2, and the Bus API's write, sync_write and
Registers.set) refuses an ID another servo answers on, and an ID two servos
already share; kmx scan flags an ID answered twice with the command that
separates them, and that command, run as the warning says (one of the two
servos alone on the bus), does separate them. On host-sim servos of
sim/bus/servo-bus (their user data kept in --flash-dir, so one of them can be
"disconnected" by starting the bus without it); the collision of two
answers on a wire, which the emulated bus does not model (it hands both
answers over whole), through a transport that ANDs them as an idle-high
wire does. About 10 s."""
import os
import re
import shlex
import subprocess
import sys
import tempfile
import unittest

from test_kmx import REPO, host_sim_image
from test_kmx_cli import KMX, kmx
from kmx import frame as fr
from kmx.bus import Bus
from kmx.errors import IdTaken
from kmx.registers import Registers
from kmx.transport import Transport

SERVO_BUS = os.path.join(REPO, "sim", "bus", "servo-bus")


class KeptBus:
    """sim/bus/servo-bus --backend host-sim with the servos' user data in
    flash_dir (servo-ID.flash), on a given TCP port (0: a free one)."""

    def __init__(self, ids, flash_dir, port=0):
        host_sim_image()
        self.proc = subprocess.Popen(
            [sys.executable, SERVO_BUS, "--ids", ",".join(map(str, ids)), "--port", str(port),
             "--backend", "host-sim", "--gap-floor-us", "0", "--flash-dir", flash_dir],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        line = self.proc.stdout.readline().split()
        if line[:1] != ["ready"]:
            self.close()
            raise AssertionError("servo-bus did not start: %r" % line)
        self.spec = "tcp:" + line[1]
        self.port = int(line[1].rsplit(":", 1)[1])

    def close(self):
        self.proc.terminate()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.proc.stdout.close()


def scan_ids(out):
    """The ID column of a kmx scan table."""
    return sorted(int(line.split()[0]) for line in out.splitlines()[1:] if re.match(r"^\d+\s+\d+\s", line))


class TakenIdRefused(unittest.TestCase):
    """Three servos, IDs 1, 2, 3: no path moves one onto another's ID."""

    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory()
        cls.wire = KeptBus((1, 2, 3), cls.dir.name)

    @classmethod
    def tearDownClass(cls):
        cls.wire.close()
        cls.dir.cleanup()

    def refused(self, message, *args):
        r = kmx(self.wire.spec, *args)
        self.assertEqual((r.returncode, r.stdout, r.stderr), (1, "", "kmx: %s\n" % message), args)

    def test_every_kmx_path(self):
        self.refused("ID 1 is taken: another servo answers there", "set", "2", "id", "1")
        self.refused("ID 3 is taken: another servo answers there", "set", "2", "0x0F", "3")
        self.refused("ID 2 is taken: another servo answers there", "set-id", "1", "2")
        # 0x03 = 2 resets the ID to 0 at once (docs/protocol-decisions.md): with
        # a servo on ID 0 already, refused too
        r = kmx(self.wire.spec, "set", "3", "userdata_reset", "2")
        self.assertEqual((r.returncode, r.stdout), (0, "userdata_reset (0x03) <- 2  [02]  (the servo answers "
                                                       "at ID 0 now)\n"), r.stderr)
        self.refused("ID 0 is taken: another servo answers there", "set", "2", "userdata_reset", "2")
        self.assertEqual(kmx(self.wire.spec, "set-id", "0", "3").returncode, 0)
        r = kmx(self.wire.spec, "scan")
        self.assertEqual((r.returncode, scan_ids(r.stdout)), (0, [1, 2, 3]), r.stdout + r.stderr)
        self.assertNotIn("warning", r.stdout)

    def test_bus_api(self):
        sent = []
        with Bus(self.wire.spec, trace=lambda way, item: sent.append(item) if way == "tx" else None) as bus:
            for n, write in enumerate((lambda: bus.write(2, fr.REG_ID, b"\x01"),
                          lambda: bus.write(2, fr.REG_ID, b"\x03", answer=True),
                          lambda: bus.sync_write(2, fr.REG_ID, b"\x01"),
                          lambda: Registers(bus).set(2, "id", 3),
                          lambda: bus.write(fr.ID_BROADCAST, fr.REG_ID, b"\x07"))):
                with self.subTest(write=n):
                    del sent[:]
                    with self.assertRaises(IdTaken):
                        write()
                    # only questions went out (pings, reads of 0x01, a scan)
                    self.assertEqual([f[4] for f in sent if f[4] in (fr.WRITE, fr.SYNC_WRITE)], [])
            bus.execute()  # a sync write that slipped through would act now
            self.assertEqual(sorted(i for i, _ in bus.scan()), [1, 2, 3])
            # a free ID and the servo's own ID pass
            bus.write(2, fr.REG_ID, b"\x02")
            bus.write(2, fr.REG_ID, b"\x09")
            self.assertEqual(bus.ping(9), 0)
            bus.write(9, fr.REG_ID, b"\x02")
            self.assertEqual(bus.ping(2), 0)


class SharedIdFlaggedAndSeparated(unittest.TestCase):
    def test_scan_warns_and_its_command_separates_them(self):
        with tempfile.TemporaryDirectory() as d:
            wire = KeptBus((1, 2, 3), d)
            try:
                port = wire.port
                with Bus(wire.spec) as bus:
                    # a raw frame, below every check: servo 2 takes ID 1
                    bus.transact(fr.write(2, fr.REG_ID, b"\x01"))
                    self.assertEqual(bus.shared_id(3), None)
                    self.assertRegex(bus.shared_id(1), r"^2 answers to one read of 0x01 \(random bytes "
                                                       r"0x[0-9A-F]{2}, 0x[0-9A-F]{2}\)$")
                r = kmx(wire.spec, "scan")
                self.assertEqual((r.returncode, r.stderr, scan_ids(r.stdout)), (0, "", [1, 1, 3]))
                lines = r.stdout.splitlines()
                self.assertRegex(lines[4], r"^3 servos on %s \(super-ID scan, \d+ ms\)" % re.escape(wire.spec))
                self.assertRegex(lines[5], r"^warning: ID 1 gave 2 answers to one read of 0x01 \(random bytes "
                                           r"0x[0-9A-F]{2}, 0x[0-9A-F]{2}\): two servos share ID 1\. No command "
                                           r"reaches one of them alone .*disconnect all but one of the servos "
                                           r"on ID 1, run$")
                self.assertEqual(lines[6], "  kmx --bus %s set-id 1 2" % wire.spec)
                self.assertEqual(lines[7], "then reconnect the others (repeat while ID 1 answers twice).")
                command = shlex.split(lines[6])
                # neither path moves both servos to one new ID
                r = kmx(wire.spec, "set-id", "1", "4")
                self.assertEqual(r.returncode, 1)
                self.assertRegex(r.stderr, r"^kmx: two servos answer on ID 1, which gave 2 answers to one read "
                                           r"of 0x01 \(random bytes .*\): the write would move both to ID 4; "
                                           r"disconnect all but one of them first\n$")
                r = kmx(wire.spec, "set", "1", "id", "4")
                self.assertEqual(r.returncode, 1)
                self.assertIn("two servos answer on ID 1", r.stderr)
            finally:
                wire.close()
            # As the warning says: servo 2's flash (stored ID 1) alone on the bus,
            # the printed command, then every servo back.
            alone = KeptBus((2,), d, port)
            try:
                r = subprocess.run([KMX] + command[1:], capture_output=True, text=True, timeout=30)
                self.assertEqual(r.returncode, 0, r.stderr)
                self.assertRegex(r.stdout, r"^ID 1 -> 2: answers at ID 2 after a restart")
            finally:
                alone.close()
            wire = KeptBus((1, 2, 3), d, port)
            try:
                r = kmx(wire.spec, "scan")
                self.assertEqual((r.returncode, scan_ids(r.stdout)), (0, [1, 2, 3]), r.stdout + r.stderr)
                self.assertNotIn("warning", r.stdout)
            finally:
                wire.close()


class AndWire(Transport):
    """Two servos on ID 5 on a real wire: their answers start together and
    the line carries the AND of their bits (idle high, either drives low).
    A ping's two answers are the same bytes and come through whole; two
    answers to a read of 0x01 differ in the random byte (§5.1) and come
    through garbled. Nothing else answers."""

    spec = "and-wire"

    def __init__(self):
        self.pending = b""
        self.randoms = iter(range(0x10, 0x100, 7))

    def write(self, data):
        if data == fr.ping(5):
            self.pending += fr.encode_status(5, 0)
        elif data in (fr.read(5, fr.REG_STATUS), fr.read(fr.ID_SUPER, fr.REG_STATUS)):
            a = fr.encode_response(5, fr.READ, fr.REG_STATUS, bytes([0, next(self.randoms)]))
            b = fr.encode_response(5, fr.READ, fr.REG_STATUS, bytes([0, next(self.randoms)]))
            self.pending += bytes(x & y for x, y in zip(a, b))
        elif data == fr.ping(fr.ID_SUPER):
            self.pending += fr.encode_status(5, 0)

    def read(self, timeout):
        out, self.pending = self.pending, b""
        return out

    def flush_input(self):
        self.pending = b""

    def close(self):
        pass


class CollidingAnswers(unittest.TestCase):
    def test_garbled_reads_count_as_two_servos(self):
        bus = Bus(AndWire(), timeout=0.02)
        self.assertEqual(bus.ping(5), 0)  # identical answers: one clean frame
        self.assertEqual(bus.shared_id(5), "garbled answers to 3 reads of 0x01 (answers colliding)")
        self.assertEqual(bus.shared_ids(bus.scan(timeout=0.02)),
                         {5: "garbled answers to 3 reads of 0x01 (answers colliding)"})
        with self.assertRaisesRegex(IdTaken, r"^two servos answer on ID 5, which gave garbled answers"):
            bus.write(5, fr.REG_ID, b"\x06")


if __name__ == "__main__":
    unittest.main()
