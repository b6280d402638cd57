# SPDX-License-Identifier: Apache-2.0
"""kmx's transports through pyserial's serial_for_url (issue 23 item 4):
a bare device path, loop://, spy:// (a hex trace of every byte), hwgrep://
(an adapter by its description), socket:// and the tcp:HOST:PORT alias with
servo-bus's busy message, each opened and used against a real host-sim
servo (a pseudo-terminal, host-sim --pty) or the 3-servo host-sim bus of
sim/bus/servo-bus. About 6 s."""
import os
import tempfile
import unittest

from test_kmx import HostSim, ServoBus
from test_kmx_cli import kmx
from kmx import transport as tp
from kmx.bus import Bus
from kmx.errors import NoAnswer, NoSuchDevice, PortBusy, SpecError


class Specs(unittest.TestCase):
    def test_pyserial_urls_and_paths(self):
        self.assertEqual(tp.parse_spec("/dev/ttyUSB0"), ("serial", {"path": "/dev/ttyUSB0", "baud": 115200}))
        self.assertEqual(tp.parse_spec("/dev/ttyUSB0@57600"), ("serial", {"path": "/dev/ttyUSB0", "baud": 57600}))
        self.assertEqual(tp.parse_spec("loop://"), ("url", {"url": "loop://", "baud": 115200}))
        self.assertEqual(tp.parse_spec("spy:///dev/ttyUSB0?file=t.txt"),
                         ("url", {"url": "spy:///dev/ttyUSB0?file=t.txt", "baud": 115200}))
        self.assertEqual(tp.parse_spec("hwgrep://FT232@1000000"), ("url", {"url": "hwgrep://FT232", "baud": 1000000}))
        self.assertEqual(tp.parse_spec("socket://127.0.0.1:7001"), ("tcp", {"host": "127.0.0.1", "port": 7001}))
        self.assertEqual(tp.parse_spec("tcp:127.0.0.1:7001"), ("tcp", {"host": "127.0.0.1", "port": 7001}))
        for bad, message in (("localhost", "expected tcp:HOST:PORT"), ("/dev/ttyUSB0@fast", "baud after @"),
                             ("gopher://x", "kmx opens no 'gopher://' URL")):
            with self.subTest(spec=bad), self.assertRaisesRegex(SpecError, message):
                tp.parse_spec(bad)

    def test_loop_hears_its_own_frames(self):
        """loop:// gives back every byte written: the bus takes them as its
        own echoes (a one-wire adapter's), never as answers."""
        with Bus("loop://", timeout=0.05, retries=0) as bus:
            with self.assertRaisesRegex(NoAnswer, "^ping ID 1: no answer from ID 1"):
                bus.ping(1)
            self.assertEqual(bus.echoes, 1)

    def test_hwgrep_without_a_match(self):
        with self.assertRaisesRegex(NoSuchDevice, "^hwgrep://no-such-adapter-kmx: no serial adapter matches "
                                                  "'no-such-adapter-kmx' \\(python3 -m serial.tools.list_ports"):
            tp.open_transport("hwgrep://no-such-adapter-kmx")


class OnAPty(unittest.TestCase):
    def setUp(self):
        self.sim = HostSim(pty=True)
        self.addCleanup(self.sim.close)
        self.path = self.sim.spec[len("pty:"):]

    def test_bare_device_path(self):
        r = kmx(self.path, "get", "0", "voltage", process=True)
        self.assertEqual((r.returncode, r.stdout), (0, "voltage (0x4B) = 7.400 V\n"), r.stderr)

    def test_spy_traces_every_byte(self):
        with tempfile.TemporaryDirectory() as d:
            log = os.path.join(d, "spy.txt")
            r = kmx("spy://%s?file=%s" % (self.path, log), "get", "0", "voltage", process=True)
            self.assertEqual((r.returncode, r.stdout), (0, "voltage (0x4B) = 7.400 V\n"), r.stderr)
            with open(log) as f:
                text = f.read()
        self.assertRegex(text, r"TX.*F9 FF 00 03 02 4B")  # the read of 0x4B, as sent
        self.assertRegex(text, r"RX.*F9 F5 00 05 02 4B E8 1C")  # its answer, 7.400 V


class OnTheEmulatedBus(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.wire = ServoBus()
        cls.hostport = cls.wire.spec[len("tcp:"):]

    @classmethod
    def tearDownClass(cls):
        cls.wire.close()

    def test_socket_url_and_busy(self):
        with Bus("socket://" + self.hostport) as bus:
            self.assertEqual(sorted(i for i, _ in bus.scan()), [1, 2, 3])
            for spec in ("socket://" + self.hostport, "tcp:" + self.hostport):
                with self.subTest(spec=spec), self.assertRaisesRegex(
                        PortBusy, "^%s: the bus is busy: another client holds it" % spec):
                    with Bus(spec, timeout=0.3, retries=0) as second:
                        second.ping(1)

    def test_a_closed_peer_leaves_no_socket(self):
        """pyserial 3.5's socket:// close leaks the socket once the peer has
        closed: kmx closes it itself (no ResourceWarning, no open fd)."""
        t = tp.open_transport("socket://" + self.hostport)
        sock = t.port._socket
        t.close()
        self.assertEqual(sock.fileno(), -1)


if __name__ == "__main__":
    unittest.main()
