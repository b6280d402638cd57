# SPDX-License-Identifier: Apache-2.0
"""tests/conformance/run_on_bus.py (what CTest's conformance entries run)
runs every check it names (issue 18 item 9): on a SCHED_FIFO bus in one
pass at the bus baud, --slow checks included; on a plain bus the --slow
ones in a second pass at --slow-baud; each named check has exactly one
result line and the closing line "total: N passed, M failed, K skipped"
counts them all. A check the suite does not report is a failure, not a
silence (tally), and conformance.py reports the checks left after a bus
error as SKIP with the reason. On real host-sim servos, about 10 s."""
import os
import re
import socket
import subprocess
import sys
import threading
import unittest

from test_kmx import REPO, host_sim_image  # noqa: E402

CONF = os.path.join(REPO, "tests", "conformance")
import run_on_bus  # noqa: E402

RUN_ON_BUS = os.path.join(CONF, "run_on_bus.py")
SUITE = os.path.join(CONF, "conformance.py")
PROBE = "import os; os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))"
# The checks CTest moves to 9600 baud on a plain bus, with one that stays.
SELECTION = ["--only", "super.", "--only", "decision:cmd.multi-read", "--only", "frame."]
SLOW = ["--slow-baud", "9600", "--slow", "super.", "--slow", "decision:cmd.multi-read"]
CLOSING = re.compile(r"total: (\d+) passed, (\d+) failed, (\d+) skipped$")


def fifo_allowed():
    return subprocess.run([sys.executable, "-c", PROBE], stderr=subprocess.DEVNULL).returncode == 0


def listed(selection):
    """The names conformance.py --list gives for this selection."""
    out = subprocess.run([sys.executable, SUITE, "--list"] + selection, capture_output=True, text=True,
                         check=True).stdout.splitlines()
    return [line.split()[0] for line in out[:-1]]


def results(stdout):
    """{name: [result lines]} from a run's output."""
    found = {}
    for line in stdout.splitlines():
        m = re.match(r"(PASS|FAIL|SKIP) (\S+?)(?:: |$)", line)
        if m:
            found.setdefault(m.group(2), []).append(line)
    return found


class EveryNamedCheckRuns(unittest.TestCase):
    def run_on_bus(self, slot_timing):
        host_sim_image()
        r = subprocess.run([sys.executable, RUN_ON_BUS, "--backend", "host-sim", "--gap-floor-us", "0",
                            "--slot-timing", slot_timing, *SLOW, "--", *SELECTION],
                           capture_output=True, text=True, timeout=300)
        names = listed(SELECTION)
        self.assertEqual(len(names), 8, names)  # 4 super., 3 decision:cmd.multi-read, frame.
        found = results(r.stdout)
        self.assertEqual({n: len(found.get(n, [])) for n in names}, {n: 1 for n in names}, r.stdout)
        self.assertEqual(sorted(found), sorted(names), r.stdout)
        closing = r.stdout.strip().splitlines()[-1]
        m = CLOSING.match(closing)
        self.assertTrue(m, closing)
        passed, failed, skipped = (int(x) for x in m.groups())
        # Whether each check passes is conformance_*'s business: a host
        # stall can still swap two answers here. What this test holds is
        # that every named check ran once and the closing line counts it.
        self.assertEqual((passed + failed + skipped, skipped), (8, 0), r.stdout)
        self.assertEqual(failed, sum(line.startswith("FAIL ") for line in r.stdout.splitlines()))
        self.assertEqual(r.returncode, 1 if failed else 0, r.stdout + r.stderr[-2000:])
        return r.stdout

    @unittest.skipUnless(fifo_allowed(), "this host refuses SCHED_FIFO (not root, no rtprio limit): "
                         "run_on_bus runs a plain bus there, test_on_a_plain_bus")
    def test_on_a_sched_fifo_bus_in_one_pass(self):
        out = self.run_on_bus("realtime")
        self.assertIn("# slot timing: SCHED_FIFO bus and suite, every check at the bus baud", out)
        self.assertNotIn("switched to 9600", out)

    def test_on_a_plain_bus_the_slow_ones_at_9600(self):
        out = self.run_on_bus("plain")
        self.assertIn("# bus: servos switched to 9600 baud (7 checks)", out)


class Tally(unittest.TestCase):
    """The closing count against the checks named."""

    def test_a_named_check_without_a_result_fails(self):
        counts, skips, problems = run_on_bus.tally(
            ["a.x", "b.y", "c.z"], ["PASS a.x", "# figure", "SKIP b.y: no line rate here"])
        self.assertEqual((counts, skips), ([1, 1, 1], [("b.y", "no line rate here")]))
        self.assertEqual(problems, ["FAIL c.z: not run: the suite printed no result for it"])

    def test_two_results_for_one_check_and_one_not_named_fail(self):
        counts, _, problems = run_on_bus.tally(["a.x"], ["PASS a.x", "FAIL a.x: late", "PASS d.w"])
        self.assertEqual(counts, [1, 3, 0])
        self.assertEqual(problems, ["FAIL d.w: ran, but not one of the checks named",
                                    "FAIL a.x: 2 results for one check"])

    def test_names_with_colons(self):
        counts, _, problems = run_on_bus.tally(
            ["decision:cmd.multi-read", "decision:cmd.multi-read.subset"],
            ["PASS decision:cmd.multi-read", "FAIL decision:cmd.multi-read.subset: order 2, 1"])
        self.assertEqual((counts, problems), ([1, 1, 0], []))


class SuiteAfterABusError(unittest.TestCase):
    def test_the_checks_left_are_skipped_with_the_reason(self):
        # a bus that accepts the master and drops it at once
        server = socket.socket()
        server.bind(("127.0.0.1", 0))
        server.listen(1)
        self.addCleanup(server.close)
        threading.Thread(target=lambda: server.accept()[0].close(), daemon=True).start()
        selection = ["--only", "frame.", "--only", "cmd.ping", "--only", "super.ping"]
        r = subprocess.run([sys.executable, SUITE, "--bus", "tcp:127.0.0.1:%d" % server.getsockname()[1],
                            "--ids", "1"] + selection, capture_output=True, text=True, timeout=60)
        self.assertEqual(r.returncode, 1)
        lines = r.stdout.splitlines()
        first = listed(selection)[0]
        self.assertRegex(lines[0], r"^FAIL %s: bus error: " % re.escape(first))
        self.assertEqual(lines[1:3], ["SKIP %s: not run: the bus failed in %s" % (n, first)
                                      for n in listed(selection)[1:]])
        self.assertEqual(lines[-1], "0 passed, 1 failed, 2 skipped")


if __name__ == "__main__":
    unittest.main()
