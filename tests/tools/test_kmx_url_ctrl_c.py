# SPDX-License-Identifier: Apache-2.0
"""kmx with pyserial's URLs for the bus (rfc2217://HOST:PORT, socket://HOST:PORT)
and Ctrl-C anywhere in kmx (issue 18 item 8): one line, `kmx: interrupted`,
status 130, never a traceback, also while an RFC 2217 port closes (pyserial
joins its reader thread and sleeps 0.3 s there). On the 3-servo host-sim
bus of sim/bus/servo-bus, which takes RFC 2217 and raw TCP on one port.
About 15 s (16 runs of tools/kmx interrupted at random)."""
import os
import random
import re
import signal
import subprocess
import sys
import time
import unittest

from test_kmx import ServoBus
from test_kmx_cli import KMX, kmx
from kmx import baud as kbaud
from kmx import transport as tp
from kmx.errors import SpecError

# The line of tools/kmx that puts its Ctrl-C handler in place: a traceback
# whose frames all lie before it is the interpreter starting, before kmx runs.
with open(KMX) as f:
    HANDLER_LINE = next((n for n, line in enumerate(f, 1) if line.startswith("_signal.signal(")), 0)
RUNS = 16
KMX_FRAME = re.compile(r'File "([^"]*)", line (\d+)')


def kmx_frames(stderr):
    """Traceback frames in kmx's own code after tools/kmx's handler line."""
    out = []
    for path, line in KMX_FRAME.findall(stderr):
        if "/host/kmx/" in path or (path.endswith("tools/kmx") and int(line) > HANDLER_LINE):
            out.append((path, line))
    return out


class UrlSpecs(unittest.TestCase):
    def test_parse(self):
        self.assertEqual(tp.parse_spec("rfc2217://127.0.0.1:7001"),
                         ("rfc2217", {"host": "127.0.0.1", "port": 7001, "baud": 115200}))
        self.assertEqual(tp.parse_spec("rfc2217://localhost:7001@57600"),
                         ("rfc2217", {"host": "localhost", "port": 7001, "baud": 57600}))
        self.assertEqual(tp.parse_spec("socket://127.0.0.1:7001"), ("tcp", {"host": "127.0.0.1", "port": 7001}))
        self.assertEqual(tp.parse_spec("tcp://127.0.0.1:7001"), ("tcp", {"host": "127.0.0.1", "port": 7001}))
        for bad, message in (("rfc2217://127.0.0.1:7001?logging=debug", "no path or ?options after HOST:PORT"),
                             ("socket://127.0.0.1:7001/x", "no path or ?options after HOST:PORT"),
                             ("rfc2217://127.0.0.1", "rfc2217 wants HOST:PORT[@BAUD]"),
                             ("socket://:7001", "tcp wants HOST:PORT"),
                             ("ftp://127.0.0.1", "kmx opens no 'ftp://' URL")):
            with self.subTest(spec=bad), self.assertRaisesRegex(SpecError, re.escape(message)):
                tp.parse_spec(bad)
        # set-baud and rescue name the same port at another baud: a URL stays one
        self.assertEqual(kbaud.spec_at("rfc2217://127.0.0.1:7001", 57600), "rfc2217://127.0.0.1:7001@57600")
        self.assertEqual(tp.parse_spec("rfc2217://127.0.0.1:7001@57600")[1]["baud"], 57600)


class UrlsAndCtrlC(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.wire = ServoBus()
        cls.hostport = cls.wire.spec[len("tcp:"):]

    @classmethod
    def tearDownClass(cls):
        cls.wire.close()

    def test_pyserial_urls_open_the_bus(self):
        for spec in ("rfc2217://" + self.hostport, "socket://" + self.hostport):
            with self.subTest(spec=spec):
                r = kmx(spec, "scan", process=True)
                self.assertEqual((r.returncode, r.stderr), (0, ""))
                self.assertIn("3 servos on %s (super-ID scan" % spec, r.stdout)
                r = kmx(spec, "get", "2", "id", process=True)
                self.assertEqual((r.returncode, r.stdout), (0, "id (0x0F) = 2\n"), r.stderr)

    def test_ctrl_c_while_rfc2217_closes(self):
        """SIGINT right after the answer is printed lands in the port's close."""
        for n in range(3):
            p = subprocess.Popen([KMX, "--bus", "rfc2217:%s@115200" % self.hostport, "ping", "1"],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                 env=dict(os.environ, PYTHONUNBUFFERED="1"))  # the line as it is printed
            line = p.stdout.readline()
            p.send_signal(signal.SIGINT)
            out, err = p.communicate(timeout=20)
            self.assertRegex(line, r"^ID 1: status 0x00 \(ok\)")
            self.assertEqual((p.returncode, err), (130, "kmx: interrupted\n"))

    def test_ctrl_c_at_random_moments(self):
        """From start-up to exit of `kmx ping` over RFC 2217: every run ends
        with status 0 and nothing on stderr, or 130 and `kmx: interrupted`;
        a run stopped while the interpreter itself starts (before tools/kmx's
        first lines: killed by the signal, or a traceback in no kmx code)
        is counted apart, and most runs must reach kmx."""
        argv = [KMX, "--bus", "rfc2217:%s@115200" % self.hostport, "ping", "1"]
        t0 = time.monotonic()
        subprocess.run(argv, capture_output=True, timeout=30)
        whole = time.monotonic() - t0
        rng = random.Random(18)
        start_up = 0
        for n in range(RUNS):
            p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            time.sleep(rng.uniform(0, 1.2 * whole))
            p.send_signal(signal.SIGINT)
            out, err = p.communicate(timeout=30)
            with self.subTest(run=n, returncode=p.returncode, stderr=err):
                self.assertEqual(kmx_frames(err), [])
                if p.returncode == -signal.SIGINT or "Traceback" in err:
                    start_up += 1
                    continue
                self.assertIn((p.returncode, err), ((0, ""), (130, "kmx: interrupted\n")))
        print("%d of %d runs stopped in the interpreter's start-up" % (start_up, RUNS), file=sys.stderr)
        self.assertLess(start_up, RUNS // 3, "too few runs reached kmx: the test did not test it")


if __name__ == "__main__":
    unittest.main()
