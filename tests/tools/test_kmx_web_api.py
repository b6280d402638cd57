# SPDX-License-Identifier: Apache-2.0
"""`kmx web`'s JSON API without a browser (docs/web.md; the page itself:
kmx_web_check.py): on three host-sim servos on sim/bus/servo-bus, a scan job
with its progress, the control table with this servo's product bounds in
place of "product" and coded values in words, a write refused naming its
limit and one read back, set-id refused when the new ID is taken (the
collision check), torque in words and a 0x68 jog (one outside the travel
refused), the fault log, live samples by 0x82 on a 50 ms schedule, the page and
Debian's Chart.js served locally, a request for a bad ID answered in
words; the bench of an emulated bus (servo-bus --inject-dir, kmx web
--inject-dir): a supply sag trips the voltage protection and "back to
normal" releases it (both in the fault log), a servo moved by set-id keeps its bench at its new ID,
every bad bench request refused in words, and without
--inject-dir the bench says why it is off. Needs python3-aiohttp (Debian's
python3 runs tools/kmx). About 20 s."""
import json
import os
import random
import signal
import subprocess
import tempfile
import threading
import time
import unittest
import urllib.request

from test_kmx import REPO, ServoBus
from kmx.bench import Bench
from kmx.errors import KmxError


def start_web(spec, *extra):
    """`tools/kmx --bus SPEC web --port 0 EXTRA`: the process and its URL."""
    proc = subprocess.Popen([os.path.join(REPO, "tools", "kmx"), "--bus", spec, "web", "--port", "0", *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    if "open http" not in line:
        proc.kill()
        raise AssertionError("kmx web did not start: %r %s" % (line, proc.communicate()[1]))
    return proc, line.split("open ")[1].split()[0].rstrip("/")


def call(url, path, body=None):
    """One API request: the JSON answer."""
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(url + path, data=data, headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=30) as r:
        return json.load(r)


class WebOnBus(unittest.TestCase):
    """Three host-sim servos on servo-bus and `kmx web` on them for the
    class's tests; with `bench` both get one --inject-dir. Its stderr
    must hold no traceback at the end."""
    bench = False

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="kmx-bench-") if cls.bench else None
        extra = ("--inject-dir", cls.tmp.name) if cls.bench else ()
        cls.wire = ServoBus(extra=extra)
        try:
            cls.proc, cls.url = start_web(cls.wire.spec, *extra)
        except AssertionError:
            cls.wire.close()
            raise

    @classmethod
    def tearDownClass(cls):
        cls.proc.send_signal(signal.SIGINT)
        out, err = cls.proc.communicate(timeout=20)
        cls.wire.close()
        if cls.tmp:
            cls.tmp.cleanup()
        assert "Traceback" not in err, err


class WebApi(WebOnBus):
    def call(self, path, body=None):
        return call(self.url, path, body)

    def job(self):
        for _ in range(300):
            j = self.call("/api/job")["job"]
            if j["done"]:
                return j
            time.sleep(0.05)
        self.fail("the job did not end")

    def test_scan_job(self):
        self.assertTrue(self.call("/api/scan", {})["ok"])
        j = self.job()
        self.assertEqual((j["error"], j["progress"]), (None, 1.0))
        self.assertEqual([(s["id"], s["model"], s["status"]) for s in j["result"]],
                         [(1, "KM-SIM-P135", "ok"), (2, "KM-SIM-P135", "ok"), (3, "KM-SIM-P135", "ok")])

    def test_control_table(self):
        r = self.call("/api/servo/2/registers")
        regs = {x["name"]: x for x in r["registers"]}
        self.assertEqual(r["model"], "KM-SIM-P135")
        self.assertEqual((regs["max_current"]["fields"][0]["min"], regs["max_current"]["fields"][0]["max"]), (0, 3000))
        self.assertEqual(regs["baud"]["fields"][0]["max"], 10000)  # raw: 1,000,000 baud / 100
        self.assertEqual(regs["torque_switch"]["enum"]["2"], "on hold")
        self.assertEqual(regs["voltage"]["value"], "7.400 V")

    def test_set_refused_and_read_back(self):
        r = self.call("/api/servo/2/set", {"name": "max_current", "value": "3500"})
        self.assertEqual(r, {"ok": False, "error": "max_current: 3500 mA is above ID 2's limit 3000 mA "
                                                   "(current_max_ma of KM-SIM-P135); nothing sent"})
        r = self.call("/api/servo/2/set", {"name": "response_delay", "value": "300"})
        self.assertEqual(r, {"ok": True, "name": "response_delay", "value": "300 µs"})
        self.call("/api/servo/2/set", {"name": "response_delay", "value": "200"})

    def test_torque_and_jog(self):
        """0x64 in words, a 0x68 jog sent and one outside the travel refused before sending."""
        self.assertEqual(self.call("/api/servo/3/torque", {"state": "on"}),
                         {"ok": True, "name": "torque_switch", "value": "2 (on, holding)"})
        try:
            self.assertEqual(self.call("/api/servo/3/jog", {"angle": 10}),
                             {"ok": True, "name": "interpolate", "value": "10.0 °"})
            self.assertEqual(self.call("/api/servo/3/jog", {"angle": 500})["error"],
                             "interpolate: 500.0 ° is outside ID 3's travel -135.0..135.0 ° (KM-SIM-P135); "
                             "nothing sent")
            self.assertEqual(self.call("/api/servo/3/torque", {"state": "sideways"}),
                             {"ok": False, "error": "torque: 'sideways' is not a state; give one of off, brake, on"})
        finally:
            self.assertEqual(self.call("/api/servo/3/torque", {"state": "off"})["value"], "0 (off, free)")

    def test_fault_log_of_a_fresh_servo(self):
        self.assertEqual(self.call("/api/servo/1/faults"),
                         {"ok": True, "events": 0, "held": 0, "kept": 0, "reset": "power-on",
                          "userdata": "product defaults: flash erased (first boot)", "entries": []})

    def test_set_id_collision(self):
        r = self.call("/api/servo/3/set-id", {"new": 1})
        self.assertEqual(r, {"ok": False, "error": "ID 1 is taken: another servo answers there"})

    def test_live_by_0x82(self):
        r = self.call("/api/live/start", {"ids": [1, 2, 3], "period_ms": 50})
        self.assertEqual(r["period_ms"], 50)
        end = time.monotonic() + 60  # a loaded machine starves the sampler for a while: its samples, not a fixed wait
        while True:
            data = self.call("/api/live/data?since=0")
            if len(data["samples"]) > 5 or time.monotonic() > end:
                break
            time.sleep(0.2)
        self.call("/api/live/stop", {})
        self.assertTrue(data["ok"], data)
        self.assertGreater(len(data["samples"]), 5)
        first = data["samples"][0]["servos"]
        self.assertEqual(sorted(first), ["1", "2", "3"])
        self.assertEqual(first["1"]["voltage"], 7.4)
        times = [s["t"] for s in data["samples"]]
        self.assertEqual(times, sorted(times))
        self.assertEqual(data["asked"], 20.0)  # what the page compares the rate with, and the time a sample takes
        self.assertTrue(0 < data["took"] < 60 and all(0 < s["took"] < 60 for s in data["samples"]), data["took"])

    def test_page_and_chart_js_served_locally(self):
        with urllib.request.urlopen(self.url + "/", timeout=10) as r:
            page = r.read().decode()
        self.assertIn('src="/chart.js/chart.min.js"', page)
        self.assertNotIn("https://", page)
        with urllib.request.urlopen(self.url + "/chart.js/chart.min.js", timeout=10) as r:
            self.assertEqual(r.status, 200)

    def test_bad_requests_in_words(self):
        self.assertEqual(self.call("/api/servo/300/registers"), {"ok": False, "error": "servo ID 300 is outside 0..250"})
        self.assertEqual(self.call("/api/servo/1/set", {"name": "voltgae", "value": "1"}),
                         {"ok": False, "error": "no register named 'voltgae'; did you mean voltage?"})

    def test_bench_off_says_why(self):
        why = ("no bench: start the emulated bus with sim/bus/servo-bus --inject-dir DIR and kmx web with "
               "--inject-dir DIR")
        self.assertEqual(self.call("/api/state")["bench"], {"servos": [], "why": why})
        self.assertEqual(self.call("/api/servo/1/bench", {"preset": "sag"}), {"ok": False, "error": why})


class WebBench(WebOnBus):
    """The emulated bus's bench from the API (docs/web.md "Bench"; the
    thresholds of docs/protocol.md §5.2: 0x3C low 6 V, detection 3 s)."""
    bench = True

    def protection_until(self, what, check, seconds=30, dev_id=2):
        """Polls /api/servo/DEV_ID/protection until check(answer) holds: the answer."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            r = call(self.url, "/api/servo/%d/protection" % dev_id)
            self.assertTrue(r["ok"], r)
            if check(r):
                return r
            time.sleep(0.2)
        self.fail("%s: not within %d s (last: %s)" % (what, seconds, r))

    def test_supply_sag_trips_and_normal_releases(self):
        """§5.2: the sag trips the voltage protection (status bit 0, 0x36 bit 0), back to 7.4 V releases it."""
        state = call(self.url, "/api/state")["bench"]
        self.assertEqual((state["servos"], state["why"]), ([1, 2, 3], None))
        self.assertEqual(call(self.url, "/api/servo/2/bench", {"preset": "sag"}),
                         {"ok": True, "applied": ["supply_mv 5000"]})
        r = self.protection_until("the voltage protection trips", lambda r: r["status_byte"] & 0x01)
        self.assertEqual((r["status"], r["protecting"], r["voltage"]), ("voltage protection", "voltage", "5.000 V"))
        self.assertEqual(call(self.url, "/api/servo/2/bench", {"preset": "normal"})["applied"],
                         ["supply_mv 7400", "ambient_dc 250", "temp_dc 250", "load_mnm 0"])
        r = self.protection_until("the voltage protection releases", lambda r: r["status_byte"] == 0)
        self.assertEqual((r["status"], r["protecting"], r["voltage"]), ("ok", "none", "7.400 V"))
        log = call(self.url, "/api/servo/2/faults")  # the trip and its release in the fault log, newest first
        self.assertEqual([(e["event"], e["what"], e["supply"]) for e in log["entries"][:2]],
                         [("released by itself", "voltage", "7.400 V"), ("tripped", "voltage", "5.000 V")])

    def test_bad_bench_requests_in_words(self):
        self.assertEqual(call(self.url, "/api/servo/1/bench", {"preset": "flood"}),
                         {"ok": False, "error": "bench: no preset 'flood' (sag, overheat, normal)"})
        self.assertEqual(call(self.url, "/api/servo/1/bench", {"key": "temp_dc", "value": 99999}),
                         {"ok": False, "error": "bench: temp_dc (the winding's temperature now) takes "
                                                "-400..2000 0.1 °C, not 99999"})
        self.assertEqual(call(self.url, "/api/servo/1/bench", {"key": "humidity", "value": 1})["error"],
                         "bench: no key 'humidity' (supply_mv, ambient_dc, load_mnm, faults, temp_dc)")
        self.assertEqual(call(self.url, "/api/servo/7/bench", {"preset": "sag"})["error"],
                         "bench: no servo with a bench answers at ID 7 now (the bench's servos are at ID 1, 2, 3)")

    def test_bench_follows_set_id(self):
        """A servo moved by set-id keeps its bench: the page's ID is the one it answers at now."""
        self.assertTrue(call(self.url, "/api/servo/3/set-id", {"new": 4})["ok"])
        try:
            self.assertEqual(call(self.url, "/api/state")["bench"]["servos"], [1, 2, 4])
            self.assertEqual(call(self.url, "/api/servo/4/bench", {"key": "supply_mv", "value": 5000}),
                             {"ok": True, "applied": ["supply_mv 5000"]})
            self.protection_until("ID 4's supply at 5.0 V", lambda r: r["voltage"] == "5.000 V", dev_id=4)
            self.assertEqual(call(self.url, "/api/servo/4/bench", {"preset": "normal"})["ok"], True)
            self.protection_until("ID 4 back to normal", lambda r: r["status_byte"] == 0, dev_id=4)
            self.assertIn("bench: no servo with a bench answers at ID 3 now",
                          call(self.url, "/api/servo/3/bench", {"preset": "sag"})["error"])
        finally:
            self.assertTrue(call(self.url, "/api/servo/4/set-id", {"new": 3})["ok"])
        self.assertEqual(call(self.url, "/api/state")["bench"]["servos"], [1, 2, 3])

    def test_host_sim_refuses_what_kmx_would_not_send(self):
        """host-sim --inject checks each datagram itself (hs_scenario.c) and answers in words."""
        bench = Bench(self.tmp.name)
        for line, answer in ((b"humidity 1", "error: unknown key (supply_mv, ambient_dc, load_mnm, faults, temp_dc)"),
                             (b"supply_mv 70000", "error: value out of range for its key"),
                             (b"supply_mv", "error: expected: KEY VALUE"),
                             (b"x" * 200, "error: longer than a scenario line")):
            with self.assertRaises(KmxError) as e:
                bench._send(bench.path(3), line, 10)
            self.assertTrue(str(e.exception).endswith(": " + answer), e.exception)
        self.assertEqual(bench.inject(3, "ambient_dc", 250), "ok ambient_dc 250")


class WebCtrlC(unittest.TestCase):
    """Ctrl-C (SIGINT) stops `kmx web` with "kmx web: stopped" and status 0,
    never a traceback, also while requests are in flight: 10 runs
    interrupted at random moments (raised inside aiohttp's accepting or
    closing of a connection, KeyboardInterrupt came out as a traceback in 2
    runs of 12 before the page's loop took SIGINT over)."""

    def test_ctrl_c_while_requests_are_in_flight(self):
        wire = ServoBus()
        try:
            for run in range(10):
                proc, url = start_web(wire.spec)
                stop = threading.Event()
                threads = [threading.Thread(target=self.hammer, args=(url, stop)) for _ in range(3)]
                for t in threads:
                    t.start()
                time.sleep(random.uniform(0.2, 1.0))
                proc.send_signal(signal.SIGINT)
                out, err = proc.communicate(timeout=30)
                stop.set()
                for t in threads:
                    t.join()
                self.assertEqual((proc.returncode, out.splitlines()[-1:], "Traceback" in err),
                                 (0, ["kmx web: stopped"], False), "run %d: %s" % (run, err))
        finally:
            wire.close()

    @staticmethod
    def hammer(url, stop):
        """Requests to url until stop: a page polling its state and a live sample."""
        while not stop.is_set():
            for path in ("/api/state", "/api/live?ids=1,2,3"):
                try:
                    urllib.request.urlopen(url + path, timeout=2).read()
                except OSError:
                    pass  # the server went away: what the test does to it


if __name__ == "__main__":
    unittest.main()
