# SPDX-License-Identifier: Apache-2.0
"""The kmx command (tools/kmx -> host/kmx/cli.py) against a real host-sim
servo over TCP and over a pseudo-terminal, and on the 3-servo host-sim bus:
scan, ping, get, set, dump, torque, move, monitor, set-id, fault-log, plot, the --help of
each subcommand, and each error's one-line message and exit code
(never a traceback). Register names and units: docs/registers.json
(docs/protocol.md §5). About 12 s."""
import contextlib
import io
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest
from unittest import mock

from test_kmx import REPO, HostSim, ServoBus
from kmx import cli, deps

KMX = os.path.join(REPO, "tools", "kmx")
SUBCOMMANDS = ("scan", "ping", "get", "set", "dump", "torque", "move", "monitor", "set-id", "set-baud", "rescue",
               "fault-log", "plot", "update", "trace")


class Result:
    def __init__(self, returncode, stdout, stderr):
        self.returncode, self.stdout, self.stderr = returncode, stdout, stderr


def kmx(bus, *args, process=False, timeout=30):
    """Runs `kmx --bus BUS ARGS`: in this process through cli.main (fast;
    an exception kmx lets escape fails the test), or with process=True as
    the installed-style command tools/kmx (its shebang, Debian's python3)."""
    if process:
        r = subprocess.run([KMX, "--bus", bus, *args], capture_output=True, text=True, timeout=timeout)
        if "Traceback" in r.stderr:
            raise AssertionError("kmx %s printed a traceback:\n%s" % (" ".join(args), r.stderr))
        return Result(r.returncode, r.stdout, r.stderr)
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = cli.main(["--bus", bus, *args])
        except SystemExit as e:  # argparse: bad command line
            code = e.code
    return Result(code, out.getvalue(), err.getvalue())


AT_45 = tuple("position (0x46) = %s °\n" % v for v in ("44.9", "45.0", "45.1"))


class KmxOverTcp(unittest.TestCase):
    def setUp(self):
        self.sim = HostSim()
        self.addCleanup(self.sim.close)

    def ok(self, *args, process=False):
        r = kmx(self.sim.spec, *args, process=process)
        self.assertEqual(r.returncode, 0, r.stderr)
        return r.stdout

    def fails(self, code, message, *args):
        r = kmx(self.sim.spec, *args)
        self.assertEqual(r.returncode, code, r.stdout + r.stderr)
        self.assertIn(message, r.stderr)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1 if code == 1 else 2, r.stderr)

    def test_scan_ping_get(self):
        out = self.ok("scan", "--scan-ms", "300", process=True)
        self.assertRegex(out, r"ID\s+baud\s+model\s+firmware\s+status")
        self.assertRegex(out, r"\n0\s+115200\s+KM-SIM-P135\s+0x[0-9A-F]{8}\s+ok\n")
        self.assertIn("1 servo on %s (super-ID scan" % self.sim.spec, out)
        self.assertRegex(self.ok("ping", "0"), r"^ID 0: status 0x00 \(ok\), answered in \d+\.\d ms$")
        out = self.ok("get", "0", "voltage", "0x0B", "position", "--raw")
        self.assertEqual(out.splitlines(), ["voltage (0x4B) = 7.400 V  [E8 1C]",
                                            "protocol_version (0x0B) = 0x05020000  [00 00 02 05]",
                                            "position (0x46) = 0.0 °  [00 00]"])

    def test_set_move_and_read_back(self):
        self.assertEqual(self.ok("set", "0", "torque_switch", "2"), "torque_switch (0x64) = 2\n")
        self.assertEqual(self.ok("set", "0", "temp_limits", "70", "5"), "temp_limits (0x3D) = 70 °C, 5 °C\n")
        self.assertEqual(self.ok("set", "0", "move_time", "45", "300"),
                         "move_time (0x65) <- 45.0 °, 300 ms  [C2 01 2C 01]\n")
        # within one count (0.1 °): host-sim's realistic plant has the pot's
        # noise and the arrive band (docs/plant.md, docs/tuning.md)
        deadline = time.monotonic() + 3
        while True:
            out = self.ok("get", "0", "position")
            if out in AT_45 or time.monotonic() > deadline:
                break
            time.sleep(0.1)
        self.assertIn(out, AT_45)

    def test_set_id_then_scan_finds_it(self):
        self.assertEqual(self.ok("set", "0", "id", "5"), "id (0x0F) = 5  (the servo answers at ID 5 now)\n")
        self.assertRegex(self.ok("scan", "--scan-ms", "300"), r"\n5\s+115200\s+KM-SIM-P135")
        self.assertIn("takes effect after restart", self.ok("set", "5", "baud", "57600"))

    def test_dump(self):
        out = self.ok("dump", "0").splitlines()
        self.assertRegex(out[0], r"^adr\s+name\s+value\s+meaning$")
        self.assertEqual(len(out), 1 + 47)  # every register of docs/protocol.md §5 this firmware has
        rows = {re.split(r"\s{2,}", line)[1]: re.split(r"\s{2,}", line)[2] for line in out[1:]}
        self.assertEqual(rows["voltage"], "7.400 V")
        self.assertEqual(rows["temp_limits"], "60 °C, 5 °C")
        self.assertEqual(rows["prot_state"], "84 (0x54)")
        self.assertEqual(rows["move_time"], "(write-only)")
        self.assertEqual(rows["product_info"], "KM-SIM-P135")

    def test_torque_and_move(self):
        self.assertEqual(self.ok("torque", "0", "off"), "ID 0: torque_switch (0x64) = 0 (off, free)\n")
        # §5.4: rotation commands run only with 0x64 = 2 or 3; §4 bit 6 otherwise
        self.fails(1, "kmx: ID 0 refused move_time = 30.0 °, 300 ms: status 0x40 (command failed)",
                   "move", "0", "30", "--time", "300")
        self.assertEqual(self.ok("torque", "0", "on"), "ID 0: torque_switch (0x64) = 2 (on, holding)\n")
        self.assertRegex(self.ok("move", "0", "30", "--time", "300", "--wait"),
                         r"^ID 0: move_time <- 30.0 °, 300 ms; stopped at (29\.[5-9]|30\.[0-5]) ° after \d+ ms\n$")
        self.assertRegex(self.ok("move", "0", "-20", "--speed", "200", "--wait"),
                         r"^ID 0: move_speed <- -20.0 °, 200 °/s; stopped at -(19\.[5-9]|20\.[0-5]) ° after \d+ ms\n$")
        self.assertEqual(self.ok("move", "0", "10"), "ID 0: move_time <- 10.0 °\n")
        self.fails(1, "kmx: move_time: 3276.8 ° is outside -3276.8 °..3276.7 °", "move", "0", "3276.8")

    def test_monitor(self):
        out = self.ok("monitor", "0", "--csv", "--count", "3", "--interval", "50").splitlines()
        self.assertEqual(out[0], "t_s,id,position_deg,speed_dps,current_ma,temperature_c,voltage_v,status")
        self.assertEqual(len(out), 4)
        for line in out[1:]:
            t, dev_id, pos, speed, cur, temp, volt, status = line.split(",")
            self.assertEqual((dev_id, temp, status), ("0", "25", "ok"))
            self.assertRegex(pos, r"^-?\d+\.\d$")
            self.assertRegex(volt, r"^\d+\.\d{3}$")
        out = self.ok("monitor", "0", "--count", "2", "--interval", "50")
        self.assertEqual(len(re.findall(r"^t = \d+\.\d\d s \(sample every 50 ms, 0x82[^)]*\)\nID\s+position\s+speed\s+current\s+temperature"
                                        r"\s+voltage\s+status\n0\s+-?0\.[01] °\s+-?[0-5] °/s", out, re.M)), 2, out)

    def test_set_id_survives_restart(self):
        self.assertRegex(self.ok("set-id", "0", "4"), r"^ID 0 -> 4: answers at ID 4 after a restart \(\d+ ms\)\n$")
        self.assertRegex(self.ok("scan", "--scan-ms", "300"), r"\n4\s+115200\s+KM-SIM-P135")
        self.fails(1, "kmx: ID 4 already is 4", "set-id", "4", "4")
        self.fails(1, "kmx: ping ID 7: no answer from ID 7 within 100 ms (3 tries)", "set-id", "7", "3")

    def test_fault_log(self):
        self.assertEqual(self.ok("fault-log", "0"),
                         "ID 0: 0 events recorded, 0 held (0 from before the last reset); last reset: power-on; "
                         "user data: product defaults: flash erased (first boot)\nno entries\n")
        # §5.2: a current threshold of 50 mA over 0.1 s trips during a move
        # and releases by itself (0x33 = 0) once the move is over: on the
        # realistic plant (host-sim's default, docs/plant.md) this move draws
        # 56..82 mA while cruising and more while accelerating, the hold
        # after it 25 mA on average (above 50 mA for at most 10 ms at a time)
        self.ok("set", "0", "current_limit", "50", "0.1")
        self.ok("torque", "0", "on")
        self.ok("move", "0", "90", "--time", "200")
        deadline = time.monotonic() + 3
        while True:
            out = self.ok("fault-log", "0")
            if "2 held" in out or time.monotonic() > deadline:
                break
            time.sleep(0.1)
        lines = out.splitlines()
        self.assertTrue(lines[0].startswith("ID 0: 2 events recorded, 2 held (0 from before the last reset)"), out)
        self.assertRegex(lines[1], r"^#\s+boot\s+t_ms\s+event\s+what\s+supply\s+current\s+temperature\s+position$")
        self.assertRegex(lines[2], r"^0\s+this\s+\d+\s+released by itself\s+current\s+\d\.\d{3} V\s+-?\d+ mA\s+25\.0 °C")
        self.assertRegex(lines[3], r"^1\s+this\s+\d+\s+tripped\s+current\s+\d\.\d{3} V\s+(\d+) mA\s+25\.0 °C")
        self.assertGreater(int(re.search(r"(\d+) mA", lines[3]).group(1)), 50)  # above the threshold

    def test_plot_step_and_trace(self):
        self.ok("torque", "0", "on")
        with tempfile.TemporaryDirectory() as d:
            png = os.path.join(d, "step.png")
            self.assertRegex(self.ok("plot", "0", "--out", png, "--seconds", "0.8", "--step", "45", "--time", "300",
                                     process=True),
                             r"^wrote %s: \d+ samples of position, speed, current over 0\.8 s; "
                             r"within 0\.5 ° of 45\.0 ° from \d+ ms\n$" % re.escape(png))
            with open(png, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
            self.assertGreater(os.path.getsize(png), 10000)
            png = os.path.join(d, "trace.png")
            self.assertRegex(self.ok("plot", "0", "--out", png, "--seconds", "0.2", process=True),
                             r"^wrote .*trace.png: \d+ samples of position, speed, current over 0\.2 s\n$")
            self.assertTrue(os.path.isfile(png))

    def test_plot_without_matplotlib_names_the_package(self):
        err = io.StringIO()
        with mock.patch.dict(sys.modules, {"matplotlib": None, "matplotlib.pyplot": None}), \
                mock.patch.object(deps, "DEBIAN_DIST_PACKAGES", "/nonexistent"), \
                contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()), \
                tempfile.TemporaryDirectory() as d:
            code = cli.main(["--bus", self.sim.spec, "plot", "0", "--out", os.path.join(d, "x.png"),
                             "--seconds", "0.05"])
        self.assertEqual((code, err.getvalue()), (1, "kmx: plot needs matplotlib: apt-get install "
                                                      "python3-matplotlib (and run with /usr/bin/python3), or pip install "
                                                      "matplotlib\n"))

    def test_ctrl_c(self):
        """Ctrl-C ends a live monitor quietly (exit 0) and any other command
        with one line, `kmx: interrupted` (exit 130), never a traceback."""
        p = subprocess.Popen([KMX, "--bus", self.sim.spec, "monitor", "0", "--interval", "50"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        p.stdout.readline()  # the first table is out: it is in its loop
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=10)
        self.assertEqual((p.returncode, err), (0, ""))
        p = subprocess.Popen([KMX, "--bus", self.sim.spec, "--timeout", "2000", "--retries", "9", "ping", "9"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(1.0)  # past start-up, waiting for an answer that does not come
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=10)
        self.assertEqual((p.returncode, out, err), (130, "", "kmx: interrupted\n"))

    def test_errors(self):
        self.fails(1, "kmx: max_current: 60000 mA is above ID 0's limit 3000 mA (current_max_ma of KM-SIM-P135); "
                      "nothing sent", "set", "0", "max_current", "60000")
        # a cross-field rule only the servo knows (hysteresis above the trip): its own refusal, bit 6
        self.fails(1, "kmx: ID 0 refused temp_limits (0x3D) = 50 60: status 0x40 (command failed)",
                   "set", "0", "temp_limits", "50", "60")
        self.fails(1, "kmx: torque_switch: 9 is outside 0..3", "set", "0", "torque_switch", "9")
        self.fails(1, "kmx: firmware_version (0x0C) is read-only", "set", "0", "firmware_version", "1")
        self.fails(1, "kmx: move_time (0x65) is write-only", "get", "0", "move_time")
        self.fails(1, "kmx: no register named 'posiiton'; did you mean position?", "get", "0", "posiiton")
        self.fails(1, "kmx: no register at address 0x20 (reserved)", "get", "0", "0x20")
        self.fails(1, "kmx: ping ID 9: no answer from ID 9 within 100 ms (3 tries)", "ping", "9")
        self.fails(2, "argument id: servo ID 300 is outside 0..250", "ping", "300")
        self.fails(2, "the following arguments are required: VALUE", "set", "0", "id")


class KmxOnThreeServos(unittest.TestCase):
    """The 3-servo host-sim bus of sim/bus/servo-bus, IDs 1, 2, 3."""

    @classmethod
    def setUpClass(cls):
        cls.wire = ServoBus()

    @classmethod
    def tearDownClass(cls):
        cls.wire.close()

    def test_scan_monitor_set_id_taken(self):
        r = kmx(self.wire.spec, "scan", "--scan-ms", "300")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(sorted(line.split()[0] for line in r.stdout.splitlines()[1:4]), ["1", "2", "3"])
        self.assertIn("3 servos on %s" % self.wire.spec, r.stdout)
        r = kmx(self.wire.spec, "monitor", "1", "2", "3", "--csv", "--count", "1")
        self.assertEqual([line.split(",")[1] for line in r.stdout.splitlines()[1:]], ["1", "2", "3"])
        r = kmx(self.wire.spec, "set-id", "1", "2")
        self.assertEqual((r.returncode, r.stderr), (1, "kmx: ID 2 is taken: another servo answers there\n"))

    def test_monitor_reads_by_0x82_on_a_schedule(self):
        """monitor: one multi-ID read (0x82) per register for all servos (6
        per sample: position, speed, current, temperature, voltage, status),
        and sample n starts at n x --interval, not after it plus the reads."""
        r = kmx(self.wire.spec, "--trace", "monitor", "1", "2", "3", "--csv", "--count", "4", "--interval", "150",
                process=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        sent = [line.split()[1:] for line in r.stderr.splitlines() if line.startswith("> ")]
        multi = [f for f in sent if f[2] == "FE" and f[4] == "82"]
        self.assertEqual(len(multi), 6 * 4, r.stderr)
        self.assertEqual(sorted({f[5] for f in multi}), ["01", "46", "47", "48", "4A", "4B"])
        times = sorted({float(line.split(",")[0]) for line in r.stdout.splitlines()[1:]})
        self.assertEqual(len(times), 4, r.stdout)
        for n, t in enumerate(times):
            self.assertGreaterEqual(t, n * 0.150 - 0.002, times)  # never before its slot

    def test_monitor_interval_is_the_sample_period(self):
        """In virtual time (each sample takes 40 ms of it): sample n starts
        at n x 150 ms, not n x (150 + 40) ms."""
        clock = [100.0]
        fake_time = mock.Mock(monotonic=lambda: clock[0], sleep=lambda s: clock.__setitem__(0, clock[0] + s))
        real_sample = cli.monitor_sample

        def sample_taking_40_ms(*args):
            clock[0] += 0.040
            return real_sample(*args)
        with mock.patch.object(cli, "time", fake_time), mock.patch.object(cli, "monitor_sample", sample_taking_40_ms):
            r = kmx(self.wire.spec, "monitor", "1", "2", "--csv", "--count", "4", "--interval", "150")
        self.assertEqual(r.returncode, 0, r.stderr)
        times = [line.split(",")[0] for line in r.stdout.splitlines()[1:]]
        self.assertEqual(times, ["0.000", "0.000", "0.150", "0.150", "0.300", "0.300", "0.450", "0.450"])


    def session(self, *args):
        """Runs tools/servo-session on this bus; returns its stdout."""
        r = subprocess.run([os.path.join(REPO, "tools", "servo-session"), "--tcp", self.wire.spec[len("tcp:"):]]
                           + list(args), capture_output=True, text=True, timeout=60)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertNotIn("Traceback", r.stderr)
        return r.stdout

    def test_servo_session_read_only_by_default(self):
        """Without --move servo-session sends no write frame (instruction 0x03)
        and no motion: safe on a real robot (issue 18 item 12)."""
        out = self.session()
        sent = [line.split(" > ")[1].split() for line in out.splitlines() if " > " in line]
        self.assertTrue(sent)
        self.assertEqual([f for f in sent if len(f) > 4 and f[1] == "FF" and f[4] == "03"], [])
        self.assertNotIn("-- move", out)
        self.assertIn("-- read only: nothing written, nothing moved", out)
        self.assertIn("id 1 position (0x46) =", out)

    def test_servo_session_decodes_with_units(self):
        """tools/servo-session --move (the demo's session) on kmx: frames and
        decoded answers; the setting it writes is put back."""
        before = kmx(self.wire.spec, "get", "1", "response_delay").stdout
        out = self.session("--move")
        self.assertIn("< F9 F5 01 02 00 FC   id 1 status 0x00 ok", out)
        self.assertRegex(out, r"< F9 F5 02 07 02 0B 00 00 02 05 E2   id 2 protocol_version \(0x0B\) = 0x05020000")
        self.assertIn("id 1 response_delay (0x12) = 250 µs", out)
        self.assertEqual(kmx(self.wire.spec, "get", "1", "response_delay").stdout, before)
        self.assertRegex(out, r"-- id 1 arrived: 4[45]\.\d ° \(asked 45\.0 ° in 500 ms\)")  # within 1.0°
        self.assertRegex(out, r"-- id 1 arrived: -?0\.\d ° \(asked 0\.0 ° at 180 °/s\)")
        for i in (1, 2, 3):
            self.assertRegex(out, r"-- id %d arrived: .* \(asked -?\d+\.0 °\)" % i)
            self.assertIn("id %d voltage (0x4B) = 7.400 V" % i, out)
        self.assertNotIn("(no answer)", out)
        self.assertNotIn("did not arrive", out)


class KmxErrorsWithoutServo(unittest.TestCase):
    def test_bus_errors(self):
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        s.close()
        cases = [("tcp:127.0.0.1:%d" % port, "kmx: tcp:127.0.0.1:%d: connection refused" % port),
                 ("tcp:7000", "kmx: bus 'tcp:7000': tcp wants HOST:PORT"),
                 ("com3", "kmx: bus 'com3': expected tcp:HOST:PORT, serial:/dev/ttyUSB0@115200, pty:/dev/pts/N or rfc2217:HOST:PORT@115200"),
                 ("serial:/dev/ttyUSB97@115200", "kmx: serial:/dev/ttyUSB97@115200: no such device /dev/ttyUSB97"),
                 ("serial:/dev/null", "kmx: serial:/dev/null: /dev/null is not a serial port")]
        for bus, msg in cases:
            with self.subTest(bus=bus):
                r = kmx(bus, "scan", process=True)
                self.assertEqual(r.returncode, 1)
                self.assertTrue(r.stderr.startswith(msg), r.stderr)
                self.assertEqual(len(r.stderr.splitlines()), 1, r.stderr)

    def test_option_without_value_and_unknown_command(self):
        for argv, msg in ((["--bus"], "argument --bus: expected one argument"),
                          (["scan", "--scan-ms"], "argument --scan-ms: expected one argument"),
                          (["frobnicate"], "argument COMMAND: invalid choice: 'frobnicate'"),
                          (["get", "1"], "the following arguments are required: NAME"),
                          (["monitor", "1", "--count", "0"], "'0' is not a count of 1 or more"),
                          (["plot", "1", "--out", "x.png", "--seconds", "-1"], "'-1' is not a positive number of seconds"),
                          (["--timeout", "nan", "ping", "1"], "'nan' is not a positive number of milliseconds")):
            err = io.StringIO()
            with self.subTest(argv=argv), contextlib.redirect_stderr(err), self.assertRaises(SystemExit) as cm:
                cli.main(argv)
            self.assertEqual(cm.exception.code, 2)
            self.assertIn(msg, err.getvalue())

    def test_help_of_every_subcommand(self):
        for sub in SUBCOMMANDS:
            with self.subTest(sub=sub):
                out = io.StringIO()
                with contextlib.redirect_stdout(out), self.assertRaises(SystemExit) as cm:
                    cli.main([sub, "--help"])
                self.assertEqual(cm.exception.code, 0)
                self.assertTrue(out.getvalue().startswith("usage: kmx %s" % sub), out.getvalue())
        r = subprocess.run([KMX, "--help"], capture_output=True, text=True, timeout=10)
        self.assertEqual(r.returncode, 0)
        for sub in SUBCOMMANDS:
            self.assertIn(sub, r.stdout)


class KmxOverPty(unittest.TestCase):
    def test_scan_and_get(self):
        sim = HostSim(pty=True)
        self.addCleanup(sim.close)
        r = kmx(sim.spec, "scan", "--scan-ms", "300")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stdout, r"\n0\s+115200\s+KM-SIM-P135\s+0x[0-9A-F]{8}\s+ok\n")
        r = kmx(sim.spec, "get", "0", "temperature")
        self.assertEqual((r.returncode, r.stdout), (0, "temperature (0x4A) = 25 °C\n"))


if __name__ == "__main__":
    unittest.main()
