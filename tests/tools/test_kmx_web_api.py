# SPDX-License-Identifier: Apache-2.0
"""`kmx web`'s JSON API without a browser (docs/web.md; the page itself:
kmx_web_check.py): on three host-sim servos on sim/bus/servo-bus, a scan job
with its progress, the control table with this servo's product bounds in
place of "product" and coded values in words, a write refused naming its
limit and one read back, set-id refused when the new ID is taken (the
collision check), live samples by 0x82 on a 50 ms schedule, the page and
Debian's Chart.js served locally, a request for a bad ID answered in
words. Needs python3-aiohttp (Debian's python3 runs tools/kmx). About 6 s."""
import json
import os
import signal
import subprocess
import time
import unittest
import urllib.request

from test_kmx import REPO, ServoBus


class WebApi(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.wire = ServoBus()
        cls.proc = subprocess.Popen([os.path.join(REPO, "tools", "kmx"), "--bus", cls.wire.spec, "web", "--port", "0"],
                                    stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = cls.proc.stdout.readline()
        if "open http" not in line:
            cls.tearDownClass()
            raise AssertionError("kmx web did not start: %r" % line)
        cls.url = line.split("open ")[1].split()[0].rstrip("/")

    @classmethod
    def tearDownClass(cls):
        cls.proc.send_signal(signal.SIGINT)
        out, err = cls.proc.communicate(timeout=20)
        cls.wire.close()
        assert "Traceback" not in err, err

    def call(self, path, body=None):
        data = None if body is None else json.dumps(body).encode()
        req = urllib.request.Request(self.url + path, data=data, headers={"Content-Type": "application/json"})
        with urllib.request.urlopen(req, timeout=30) as r:
            return json.load(r)

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

    def test_set_id_collision(self):
        r = self.call("/api/servo/3/set-id", {"new": 1})
        self.assertEqual(r, {"ok": False, "error": "ID 1 is taken: another servo answers there"})

    def test_live_by_0x82(self):
        r = self.call("/api/live/start", {"ids": [1, 2, 3], "period_ms": 50})
        self.assertEqual(r["period_ms"], 50)
        time.sleep(1.5)
        data = self.call("/api/live/data?since=0")
        self.call("/api/live/stop", {})
        self.assertTrue(data["ok"], data)
        self.assertGreater(len(data["samples"]), 5)
        first = data["samples"][0]["servos"]
        self.assertEqual(sorted(first), ["1", "2", "3"])
        self.assertEqual(first["1"]["voltage"], 7.4)
        times = [s["t"] for s in data["samples"]]
        self.assertEqual(times, sorted(times))

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


if __name__ == "__main__":
    unittest.main()
