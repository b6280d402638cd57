#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""The example scripts of docs/python-api.md (host/examples/*.py) run as a
user runs them, against three real host-sim servos (IDs 1, 2, 3) on the
emulated bus of sim/bus/servo-bus: each exits 0, prints no traceback, and
prints what the tutorial says it prints. Every example in host/examples/
must have its check here (a new one without fails). CTest kmx_examples;
needs the host-sim preset built. About 10 s.
    kmx_examples_check.py [-v]"""
import glob
import os
import re
import subprocess
import sys
import unittest

from test_kmx import REPO, ServoBus

EXAMPLES = os.path.join(REPO, "host", "examples")
EXPECT = {  # example -> regular expressions its output must match, in order
    "scan.py": [r"^3 servos on tcp:", r"^ID 1: KM-SIM-P135, firmware 0x[0-9A-F]{8}, 7\.400 V, status: ok$",
                r"^ID 3: KM-SIM-P135"],
    "registers.py": [r"^max_speed is \d+ °/s \(the number: \d+\)$", r"^after set: 300 °/s$",
                     r"^refused: max_speed: 5000 °/s is above ID 1's limit 360 °/s \(speed_max_dps of KM-SIM-P135\); "
                     r"nothing sent$", r"^restored: \d+ °/s$"],
    "group.py": [r"^voltage of \[1, 2, 3\] in one 0x82 frame: \{1: '7\.400 V', 2: '7\.400 V', 3: '7\.400 V'\}$",
                 r"^positions: \{1: '", r"^back at: \{1: '-?0\.\d °', 2: '-?0\.\d °', 3: '-?0\.\d °'\}$"],
    "move.py": [r"^arrived at 4[45]\.\d °$", r"^arrived at -(29|30|31)\.\d °$",
                r"^refused: move_time: 170\.0 ° is outside ID 1's travel -135\.0\.\.135\.0 ° \(KM-SIM-P135\); "
                r"nothing sent$"],
    "faults.py": [r"^fault log of ID 1: \d+ entries$", r"^ID 99: NoAnswer: read 0x4B of ID 99: no answer",
                  r"^a misspelt name: RegisterError: no register named 'voltgae'; did you mean voltage",
                  r"^a negative speed: RangeError: max_speed: -5 °/s is outside 0 °/s\.\.",
                  r"^no bus: tcp:127\.0\.0\.1:1: connection refused"],
}


class Examples(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.wire = ServoBus()

    @classmethod
    def tearDownClass(cls):
        cls.wire.close()

    def test_every_example_is_checked(self):
        found = sorted(os.path.basename(p) for p in glob.glob(os.path.join(EXAMPLES, "*.py"))
                       if not os.path.basename(p).startswith("_"))
        self.assertEqual(found, sorted(EXPECT))

    def run_example(self, name):
        r = subprocess.run([sys.executable, os.path.join(EXAMPLES, name), "--bus", self.wire.spec],
                           capture_output=True, text=True, timeout=120, cwd="/")
        self.assertNotIn("Traceback", r.stderr)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        pos = 0
        for pattern in EXPECT[name]:
            m = re.compile(pattern, re.M).search(r.stdout, pos)
            self.assertIsNotNone(m, "%s: no line matching %r after offset %d in:\n%s" % (name, pattern, pos, r.stdout))
            pos = m.end()
        return r.stdout

    def test_scan(self):
        self.run_example("scan.py")

    def test_registers(self):
        self.run_example("registers.py")

    def test_group(self):
        self.run_example("group.py")

    def test_move(self):
        self.run_example("move.py")

    def test_faults(self):
        self.run_example("faults.py")


if __name__ == "__main__":
    unittest.main()
