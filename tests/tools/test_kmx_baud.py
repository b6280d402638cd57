# SPDX-License-Identifier: Apache-2.0
"""Baud on the emulated bus (docs/protocol-decisions.md "Baud on the
emulated bus"; docs/protocol.md §1 8N1, §3 baud change, §5.1 0x10) and the kmx
commands built on it: the mismatch model sim/bus/kmwire.py, host-sim --baud,
servo-bus as an RFC 2217 serial port, kmx set-baud, scan --all-bauds and
rescue on two real host-sim servos, and each refusal's one-line message.
About 30 s (the all-baud scans listen 2.2 s at 9600)."""
import os
import subprocess
import sys
import unittest

from test_kmx import REPO, HostSim, ServoBus
from test_kmx_cli import kmx
from kmx.bus import Bus
from kmx import frame as fr
from kmx.errors import NoAnswer

import kmwire

PING1 = fr.ping(1)


class Garble(unittest.TestCase):
    """What a UART at one rate decodes from 8N1 bytes sent at another."""

    def test_equal_rates_and_small_errors_pass_bytes(self):
        self.assertEqual(kmwire.garble(PING1, 115200, 115200), PING1)
        # a few per cent apart, the stop bit's middle stays inside the sent one
        self.assertEqual(kmwire.garble(PING1 * 4, 115200, 117500), PING1 * 4)
        self.assertEqual(kmwire.garble(PING1 * 4, 115200, 112900), PING1 * 4)

    def test_rates_apart_never_carry_a_frame(self):
        # More than 10 % apart (230400 and 250000, 8.5 % apart, can decode
        # some frames, as on a real wire)
        rates = (9600, 19200, 38400, 57600, 115200, 230400, 250000, 500000, 1000000)
        frames = (PING1, fr.read(1, 0x46), fr.encode_status(1, 0), fr.encode_response(1, 0x02, 0x46, b"\x10\x0e"))
        for tx in rates:
            for rx in rates:
                if max(tx, rx) < 1.1 * min(tx, rx):
                    continue
                for f in frames:
                    got = kmwire.garble(f * 3, tx, rx)
                    self.assertNotIn(fr.CMD_HEADER, got, (tx, rx, got.hex()))
                    self.assertNotIn(fr.RSP_HEADER, got, (tx, rx, got.hex()))

    def test_deterministic_and_known_values(self):
        a = kmwire.garble(PING1 * 3, 57600, 115200)
        self.assertEqual(a, kmwire.garble(PING1 * 3, 57600, 115200))
        # a slow sender's start bit reads as a 0x00 byte with a framing error
        # at 12x the rate: dropped, so 9600 -> 115200 decodes nothing at all
        self.assertEqual(kmwire.garble(PING1, 9600, 115200), b"")
        # a 0x00 byte at 115200 is 9 bit times low: a 1 Mbaud receiver reads 0x00s
        self.assertEqual(kmwire.garble(b"\x00", 115200, 1000000), b"")
        self.assertEqual(kmwire.garble(b"\x55", 1000000, 1000000), b"\x55")

    def test_baud_values(self):
        self.assertIsNone(kmwire.baud_error("115200"))
        self.assertIsNone(kmwire.baud_error(9600))
        for bad in ("0", "-9600", "abc", "9599", "1000001", "1e5", ""):
            self.assertIsNotNone(kmwire.baud_error(bad), bad)


class HostSimBaud(unittest.TestCase):
    """host-sim --baud N: the master's rate on its own wire."""

    def test_servo_at_another_baud_is_silent(self):
        sim = HostSim(extra=("--baud", "57600"))  # a fresh servo runs at 115200
        self.addCleanup(sim.close)
        with Bus(sim.spec, timeout=0.05, retries=1) as bus:
            with self.assertRaises(NoAnswer):
                bus.ping(0)

    def test_servo_at_the_bus_baud_answers(self):
        sim = HostSim(extra=("--baud", "115200"))
        self.addCleanup(sim.close)
        with Bus(sim.spec) as bus:
            self.assertEqual(bus.ping(0) & 0x60, 0)

    def test_bad_baud_is_refused(self):
        image = os.path.join(REPO, "build", "host-sim", "boards", "host-sim", "km-servo-host-sim")
        image = os.environ.get("KM_BUILD_HOST_SIM") and os.path.join(
            os.environ["KM_BUILD_HOST_SIM"], "boards", "host-sim", "km-servo-host-sim") or image
        for bad in ("0", "abc", "9599", "2000000", "-1"):
            r = subprocess.run([image, "--listen", "127.0.0.1:1", "--flash", "/nonexistent/x", "--baud", bad],
                               capture_output=True, text=True, timeout=10)
            self.assertEqual(r.returncode, 2, bad)
            self.assertEqual(r.stderr.strip().splitlines(),
                             ["host-sim: --baud '%s': a baud rate is a whole number in 9600..1000000" % bad])

    def test_servo_bus_refuses_bad_baud(self):
        for bad, why in (("abc", "'abc' is not a baud rate"), ("0", "0 baud is outside"),
                         ("2000000", "2000000 baud is outside the servos' range 9600..1000000")):
            r = subprocess.run([sys.executable, os.path.join(REPO, "sim", "bus", "servo-bus"), "--ids", "1",
                                "--port", "0", "--backend", "host-sim", "--baud", bad],
                               capture_output=True, text=True, timeout=20)
            self.assertEqual(r.returncode, 2)
            self.assertIn(why, r.stderr)
            self.assertNotIn("Traceback", r.stderr)


class BaudOnTheBus(unittest.TestCase):
    """Two host-sim servos on servo-bus: set-baud, the wire going silent at
    the old rate, scan --all-bauds, rescue, and back."""

    @classmethod
    def setUpClass(cls):
        cls.wire = ServoBus(ids=(1, 2))

    @classmethod
    def tearDownClass(cls):
        cls.wire.close()

    def test_set_baud_then_rescue(self):
        rfc = self.wire.rfc2217
        at57600 = rfc.replace("@115200", "@57600")
        r = kmx(rfc, "set-baud", "2", "57600")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stdout, r"^ID 2: baud 115200 -> 57600: answers at 57600 baud after a restart "
                         r"\(\d+ ms\); talk to it with --bus %s\n$" % at57600)
        try:
            # at the old rate the wire carries garbage: ID 2 is silent, ID 1 answers
            r = kmx(self.wire.spec, "scan")
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertRegex(r.stdout, r"(?m)^1\s+115200\s+KM-SIM")
            self.assertNotRegex(r.stdout, r"(?m)^2\s")
            r = kmx(self.wire.spec, "ping", "2")
            self.assertEqual((r.returncode, r.stderr), (1, "kmx: ping ID 2: no answer from ID 2 within 100 ms (3 tries)\n"))
            r = kmx(at57600, "ping", "2")
            self.assertEqual(r.returncode, 0, r.stderr)

            r = kmx(rfc, "rescue")
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("found ID 1 at 115200 baud (KM-SIM-P135", r.stdout)
            self.assertIn("found ID 2 at 57600 baud (KM-SIM-P135", r.stdout)
            self.assertIn("  talk to it:      kmx --bus %s ping 2\n" % at57600, r.stdout)
            self.assertIn("  back to 115200:  kmx --bus %s set-baud 2 115200\n" % at57600, r.stdout)
            self.assertRegex(r.stdout, r"2 servos found over 9 baud rates in [\d.]+ s\n$")

            r = kmx(rfc, "scan", "--all-bauds")
            self.assertEqual(r.returncode, 0, r.stderr)
            lines = r.stdout.splitlines()
            self.assertEqual(lines[0].split(), ["ID", "baud", "model", "firmware", "status"])
            self.assertEqual([ln.split()[:3] for ln in lines[1:3]],
                             [["1", "115200", "KM-SIM-P135"], ["2", "57600", "KM-SIM-P135"]])
            self.assertTrue(lines[1].endswith("ok") and lines[2].endswith("ok"), r.stdout)
        finally:
            r = kmx(at57600, "set-baud", "2", "115200")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(kmx(self.wire.spec, "ping", "2").returncode, 0)

    def test_refusals(self):
        r = kmx(self.wire.spec, "set-baud", "1", "57600")
        self.assertEqual((r.returncode, r.stderr), (1, (
            "kmx: set-baud needs a bus whose baud kmx can change; %s cannot (use --bus "
            "rfc2217:HOST:PORT@BAUD: servo-bus takes RFC 2217 on the same port)\n" % self.wire.spec)))
        r = kmx(self.wire.spec, "rescue")
        self.assertEqual(r.returncode, 1)
        self.assertIn("kmx: rescue needs a bus whose baud kmx can change", r.stderr)
        for bad, why in (("9650", "9650 baud cannot be stored: 0x10 holds baud / 100, so a multiple of 100"),
                         ("1200", "1200 baud is outside the servos' range 9600..1000000"),
                         ("fast", "'fast' is not a baud rate")):
            r = kmx(self.wire.rfc2217, "set-baud", "1", bad)
            self.assertEqual(r.returncode, 2)
            self.assertIn(why, r.stderr)
        port_spec = self.wire.rfc2217.replace("@115200", "@5")
        r = kmx(port_spec, "ping", "1")
        self.assertEqual((r.returncode, r.stderr), (1, "kmx: %s: the bus refused 5 baud (the servos run at "
                                                       "9600..1000000)\n" % port_spec))

    def test_busy_bus(self):
        import socket
        host, port = self.wire.spec.split(":")[1:]
        holder = socket.create_connection((host, int(port)))
        try:
            holder.recv(0)
            r = kmx(self.wire.spec, "ping", "1")
        finally:
            holder.close()
        self.assertEqual((r.returncode, r.stderr), (1, (
            "kmx: %s: the bus is busy: another client holds it (servo-bus takes one client at a "
            "time; close the other one)\n" % self.wire.spec)))


if __name__ == "__main__":
    unittest.main()
