#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""`kmx web` in a real browser (issue 23 item 2): Debian's Chromium,
headless, driven by Selenium (python3-selenium, chromium-driver) against
`kmx web` on three host-sim servos on sim/bus/servo-bus:
  - a scan finds the 3 servos;
  - a value edited in the control table (max_speed = 300 °/s) reads back
    over the bus (the table read again shows it);
  - a refused value (max_current = 5000 mA) shows the limit that refused it;
  - a move (torque on, slider to 60°, Move) shows on the live position plot;
then on two QEMU servos booting through the bootloader (qemu preset), an
update through the page runs to its end state ("every servo runs the new
image", both at 0x0C v2). A screenshot of each step goes to docs/web/.
Exit 77 (CTest SKIP_RETURN_CODE) with the reason when Chromium, its driver
or Selenium is missing (tools/install-deps installs them). CTest kmx_web;
about 60 s.
    kmx_web_check.py [-v] [--no-screenshots]"""
import os
import shutil
import signal
import subprocess
import sys
import time
import unittest

from test_kmx import REPO, ServoBus
from kmx.deps import import_debian
from kmx.errors import MissingPackage

SKIP = 77
SHOTS = os.path.join(REPO, "docs", "web")
QEMU_BUILD = os.path.join(os.environ.get("KM_BUILD_QEMU") or os.path.join(REPO, "build", "qemu"),
                          "boards", "qemu-microbit")
BOOT = os.path.join(QEMU_BUILD, "km-servo-boot-qemu-microbit.elf")
V2 = os.path.join(QEMU_BUILD, "km-servo-app-v2-qemu-microbit.kmfw")
SAVE = "--no-screenshots" not in sys.argv


def browser_or_skip():
    """Selenium's Chrome driver on Debian's Chromium, or exit 77 saying what is missing."""
    missing = [p for p in ("/usr/bin/chromium", "/usr/bin/chromedriver") if not os.path.exists(p)]
    try:
        webdriver = import_debian("selenium.webdriver", "python3-selenium", "kmx_web")
        from selenium.webdriver.chrome.service import Service
    except MissingPackage:
        missing.append("python3-selenium")
    if missing:
        print("kmx_web: SKIPPED: %s missing (tools/install-deps installs chromium, chromium-driver, "
              "python3-selenium)" % ", ".join(missing))
        sys.exit(SKIP)
    opts = webdriver.ChromeOptions()
    opts.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1200,1400"):
        opts.add_argument(arg)
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=opts)


class Web:
    """`tools/kmx --bus SPEC web --port 0`; its URL."""

    def __init__(self, spec):
        self.proc = subprocess.Popen([os.path.join(REPO, "tools", "kmx"), "--bus", spec, "web", "--port", "0"],
                                     stdout=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline()
        if "open http" not in line:
            self.close()
            raise AssertionError("kmx web did not start: %r" % line)
        self.url = line.split("open ")[1].split()[0]

    def close(self):
        self.proc.send_signal(signal.SIGINT)
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.proc.stdout.close()


class QemuBus:
    """Two QEMU servos booting through the bootloader (v1 in its factory slot)."""

    def __init__(self):
        for f in (BOOT, V2):
            if not os.path.isfile(f):
                raise AssertionError("missing %s: cmake --preset qemu && cmake --build --preset qemu" % f)
        self.proc = subprocess.Popen([os.path.join(REPO, "sim", "bus", "servo-bus"), "--ids", "1,2", "--port", "0",
                                      "--image", BOOT], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                     text=True)
        line = self.proc.stdout.readline()
        if not line.startswith("ready "):
            self.close()
            raise AssertionError("servo-bus (qemu) did not start: %r" % line)
        self.spec = "tcp:" + line.split()[1]

    def close(self):
        self.proc.send_signal(signal.SIGINT)
        try:
            self.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.proc.stdout.close()


class InTheBrowser(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.driver = browser_or_skip()
        cls.wire = ServoBus()
        cls.web = Web(cls.wire.spec)
        cls.driver.get(cls.web.url)
        if SAVE:
            os.makedirs(SHOTS, exist_ok=True)

    @classmethod
    def tearDownClass(cls):
        cls.driver.quit()
        cls.web.close()
        cls.wire.close()

    def el(self, id_):
        return self.driver.find_element("id", id_)

    def wait_for(self, what, check, seconds=30):
        """Polls check() (a value, falsy until it holds) for `seconds`; its value."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            got = check()
            if got:
                return got
            time.sleep(0.1)
        self.fail("%s: not within %d s" % (what, seconds))

    def shot(self, name):
        if SAVE:
            self.driver.save_screenshot(os.path.join(SHOTS, name))

    def scanned(self):
        """Scans through the page; the IDs in its servo table."""
        self.el("scan-btn").click()
        return self.wait_for("3 rows in the servo table", lambda: [
            r.find_elements("tag name", "td")[0].text
            for r in self.el("servos").find_elements("css selector", "tbody tr")] or None)

    def row(self, name):
        return self.driver.find_element("css selector", "#regs tr[data-reg='%s']" % name)

    def edit(self, name, value):
        """Types value into the control table's field for name and sets it: the result text."""
        row = self.row(name)
        field = row.find_element("css selector", "input[name=value]")
        field.clear()
        field.send_keys(value + "\n")  # Enter submits: the keyboard path
        return self.wait_for("the result of setting %s" % name, lambda: self.row(name).find_element(
            "css selector", ".result").text.strip())

    def read_table(self):
        self.el("read-table").click()
        self.wait_for("the control table", lambda: "registers" in self.el("table-msg").text)

    def test_1_scan_finds_three(self):
        self.assertEqual(self.scanned(), ["1", "2", "3"])
        self.assertIn("3 servos found", self.el("busline").text)
        self.shot("scan.png")

    def test_2_edit_reads_back_and_refusal_shows_limit(self):
        self.read_table()
        self.assertEqual(self.edit("max_speed", "300"), "→ 300 °/s")
        self.read_table()  # read again over the bus
        self.assertEqual(self.row("max_speed").find_elements("tag name", "td")[2].text, "300 °/s")
        refused = self.edit("max_current", "5000")
        self.assertEqual(refused, "max_current: 5000 mA is above ID 1's limit 3000 mA (current_max_ma of "
                                  "KM-SIM-P135); nothing sent")
        self.driver.execute_script("document.getElementById('table').scrollIntoView()")
        self.shot("control-table.png")

    def test_3_move_shows_on_the_plot(self):
        self.el("torque-on").click()
        self.wait_for("torque on", lambda: "torque_switch = 2" in self.el("servo-msg").text)
        self.el("live-btn").click()
        self.driver.execute_script("const s = document.getElementById('move-slider'); s.value = 60;"
                                   "s.dispatchEvent(new Event('input'));")
        self.el("move-btn").click()
        last = "const d = kmx.charts.position.data.datasets[0].data; return d.length ? d[d.length - 1].y : null;"
        top = self.wait_for("ID 1's position near 60° on the plot",
                            lambda: (lambda y: y if y is not None and y > 55 else None)(
                                self.driver.execute_script(last)))
        self.assertLess(top, 65)
        time.sleep(1.5)  # a rate over more than a second
        rate = self.driver.execute_script("return kmx.rate")
        print("kmx_web: live plot of 3 servos at %.1f samples/s (asked: 20)" % rate)
        self.assertGreater(rate, 10)  # 20 asked; a loaded machine may starve the emulated servos
        self.shot("plots.png")
        self.el("live-btn").click()

    def test_4_update_reaches_its_end_state(self):
        qemu = QemuBus()
        try:
            bus = self.el("bus")
            bus.clear()
            bus.send_keys(qemu.spec + "\n")
            self.wait_for("connected to the QEMU bus", lambda: qemu.spec in self.el("busline").text)
            self.el("image").send_keys(V2)
            self.el("update-ids").send_keys("1,2")
            self.el("update-btn").click()
            end = self.wait_for("the update's end state", lambda: self.el("update-end").text, 240)
            self.assertEqual(end, "done: every servo runs the new image", self.el("update-log").text)
            states = [r.text for r in self.driver.find_elements("css selector", "#update-servos tbody tr")]
            self.assertTrue(all(" updated" in s for s in states) and len(states) == 2, states)
            self.assertIn("ID 1: 0x0C = 0x10100102 (new image)", self.el("update-log").text)
            self.driver.execute_script("document.getElementById('update').scrollIntoView()")
            self.shot("update.png")
        finally:
            qemu.close()

    def test_5_phone_sized(self):
        """At 390 px wide every section is one column and nothing is wider than the window."""
        self.driver.set_window_size(390, 1600)
        try:
            width = self.driver.execute_script("return document.documentElement.scrollWidth")
            wide = self.driver.execute_script(
                "return [...document.querySelectorAll('body *')].filter(e => e.getBoundingClientRect().right > 400)"
                ".slice(0, 5).map(e => e.tagName + '#' + e.id + '.' + e.className + ' ' + "
                "Math.round(e.getBoundingClientRect().right))")
            self.assertLessEqual(width, 400, wide)
            self.driver.execute_script("window.scrollTo(0, 0)")
            self.shot("phone.png")
        finally:
            self.driver.set_window_size(1200, 1400)


if __name__ == "__main__":
    if shutil.which("chromium") is None and not os.path.exists("/usr/bin/chromium"):
        print("kmx_web: SKIPPED: chromium missing (tools/install-deps installs it)")
        sys.exit(SKIP)
    sys.argv = [a for a in sys.argv if a != "--no-screenshots"]
    unittest.main()
