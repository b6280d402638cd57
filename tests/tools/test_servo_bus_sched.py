# SPDX-License-Identifier: Apache-2.0
"""sim/bus/servo-bus's scheduling (issue 18 item 11): SCHED_FIFO by default
where the host allows it (servos at 10, the hub at 20), plain with
--no-realtime (also under a real-time parent) and where the host does not
allow it, --realtime there exits 2, and stderr says which was chosen. Real
host-sim servos; each policy is read back from the kernel
(os.sched_getscheduler) for servo-bus and for every servo process. And the
guard against a guest that busy-loops: three QEMU servos sent into the
update bootloader (which polls its UART) go to plain scheduling and all
three still answer, instead of two of them holding both cores at SCHED_FIFO
and starving the third and every ordinary process (about 10 s); and a
busy-looping process goes plain within the conformance timeout (0.5 s),
not after the 1-2 s in which it starved every other real-time servo on
the host."""
import ctypes
import os
import re
import resource
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import unittest

from test_kmx import REPO, host_sim_image  # noqa: E402
from kmx import frame as kmframe  # noqa: E402  (docs/architecture.md "The folders": PYTHONPATH)
import simbus  # noqa: E402  (sim/bus: the boards' builds, found as servo-bus finds them)

SERVO_BUS = os.path.join(REPO, "sim", "bus", "servo-bus")
BOOT_IMAGE = os.path.join(simbus.build_dir("qemu"), "boards", "qemu-microbit", "km-servo-boot-qemu-microbit.elf")
# docs/update.md §4: 0x78 ENTER and START, broadcast
ENTER = kmframe.encode_command(kmframe.ID_BROADCAST, 0x78, 0x01, bytes([0xB1, 0xB2, 0xB3, 0xB4]))
START = kmframe.encode_command(kmframe.ID_BROADCAST, 0x78, 0x07, bytes([0xE1, 0xE2, 0xE3, 0xE4]))
PROBE = "import os; os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))"
PR_CAPBSET_DROP = 24
CAP_SYS_NICE = 23


def no_realtime_here():
    """In a child before exec: a host that refuses SCHED_FIFO (no
    CAP_SYS_NICE, also for root after exec, and an rtprio limit of 0)."""
    ctypes.CDLL(None, use_errno=True).prctl(PR_CAPBSET_DROP, CAP_SYS_NICE, 0, 0, 0)  # EPERM: none to drop
    resource.setrlimit(resource.RLIMIT_RTPRIO, (0, 0))


def realtime_parent():
    """In a child before exec: SCHED_FIFO 5, as tests/conformance/run_on_bus.py runs."""
    os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(5))


def fifo_allowed(preexec=None):
    return subprocess.run([sys.executable, "-c", PROBE], stderr=subprocess.DEVNULL,
                          preexec_fn=preexec).returncode == 0


class Scheduling(unittest.TestCase):
    def start(self, *args, preexec=None):
        """servo-bus with servos 1, 2 on host-sim: its policy, its priority
        and its servos' policies once ready, and its scheduling line."""
        host_sim_image()
        p = subprocess.Popen([sys.executable, SERVO_BUS, "--ids", "1,2", "--port", "0", "--backend",
                              "host-sim", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True, preexec_fn=preexec)

        def stop():
            if p.poll() is None:
                p.terminate()
            p.communicate(timeout=30)
        self.addCleanup(stop)
        ready = p.stdout.readline()
        self.assertTrue(ready.startswith("ready 127.0.0.1:"), ready)
        err = ""
        while len(re.findall(r"pid \d+ on port", err)) < 2:  # written before ready
            err += p.stderr.readline()
        lines = [ln for ln in err.splitlines() if ln.startswith("servo-bus: scheduling: ")]
        self.assertEqual(len(lines), 1, err)
        servos = [os.sched_getscheduler(int(pid)) for pid in re.findall(r"pid (\d+) on port", err)]
        self.servo_priorities = [os.sched_getparam(int(pid)).sched_priority
                                 for pid in re.findall(r"pid (\d+) on port", err)]
        return (os.sched_getscheduler(p.pid), os.sched_getparam(p.pid).sched_priority, servos,
                lines[0])

    @unittest.skipUnless(fifo_allowed(), "this host refuses SCHED_FIFO (not root, no rtprio "
                         "limit): the default is plain there, test_not_allowed_falls_back_to_plain")
    def test_default_is_sched_fifo_where_allowed(self):
        hub, prio, servos, line = self.start()
        self.assertEqual((hub, prio, servos), (os.SCHED_FIFO, 20, [os.SCHED_FIFO] * 2))
        self.assertEqual(self.servo_priorities, [10, 10])
        self.assertEqual(line, "servo-bus: scheduling: SCHED_FIFO, servos 10, hub 20, a busy-looping "
                         "servo plain (the host allows it; --no-realtime for plain)")

    def test_no_realtime_is_plain(self):
        # from a SCHED_FIFO parent where the host allows one: plain all the same
        parent = realtime_parent if fifo_allowed() else None
        hub, _, servos, line = self.start("--no-realtime", preexec=parent)
        self.assertEqual((hub, servos), (os.SCHED_OTHER, [os.SCHED_OTHER] * 2))
        self.assertEqual(line, "servo-bus: scheduling: plain (--no-realtime)")

    def test_not_allowed_falls_back_to_plain(self):
        self.assertFalse(fifo_allowed(no_realtime_here), "could not take SCHED_FIFO away")
        hub, _, servos, line = self.start(preexec=no_realtime_here)
        self.assertEqual((hub, servos), (os.SCHED_OTHER, [os.SCHED_OTHER] * 2))
        self.assertEqual(line, "servo-bus: scheduling: plain (SCHED_FIFO not allowed here: [Errno 1] "
                         "Operation not permitted; root or an rtprio limit allows it)")

    def test_realtime_where_not_allowed_exits_2(self):
        host_sim_image()
        r = subprocess.run([sys.executable, SERVO_BUS, "--ids", "1", "--port", "0", "--backend",
                            "host-sim", "--realtime"], capture_output=True, text=True, timeout=30,
                           preexec_fn=no_realtime_here)
        self.assertEqual((r.returncode, r.stdout, r.stderr),
                         (2, "", "servo-bus: --realtime: cannot enter SCHED_FIFO ([Errno 1] Operation "
                          "not permitted); needs CAP_SYS_NICE\n"))

    def test_realtime_and_no_realtime_exclude_each_other(self):
        r = subprocess.run([sys.executable, SERVO_BUS, "--ids", "1", "--port", "0", "--realtime",
                            "--no-realtime"], capture_output=True, text=True, timeout=30)
        self.assertEqual(r.returncode, 2)
        self.assertEqual(r.stderr.splitlines()[-1], "servo-bus: error: argument --no-realtime: not "
                         "allowed with argument --realtime")



def policies(pid):
    """The scheduling policy of every thread of a process."""
    out = set()
    for tid in os.listdir("/proc/%d/task" % pid):
        try:
            out.add(os.sched_getscheduler(int(tid)))
        except OSError:
            pass
    return out


def ping(sock, dev_id, timeout):
    """True when dev_id answers a ping on the bus before the timeout."""
    sock.sendall(kmframe.ping(dev_id))
    parser, end = kmframe.Parser(), time.monotonic() + timeout
    while time.monotonic() < end:
        sock.settimeout(max(0.01, end - time.monotonic()))
        try:
            data = sock.recv(4096)
        except socket.timeout:
            return False
        if any(f.id == dev_id for f in parser.feed(data)):
            return True
    return False


def start_boot_bus(test, ids):
    """servo-bus on the QEMU bootloader image with servos `ids`, stopped at
    the test's end: its ready line and its stderr (a file)."""
    errlog = tempfile.TemporaryFile(mode="w+")
    test.addCleanup(errlog.close)
    p = subprocess.Popen([sys.executable, SERVO_BUS, "--ids", ids, "--port", "0", "--image", BOOT_IMAGE],
                         stdout=subprocess.PIPE, stderr=errlog, text=True)

    def stop():
        p.terminate()
        p.communicate(timeout=30)
    test.addCleanup(stop)
    ready = p.stdout.readline()
    test.assertTrue(ready.startswith("ready 127.0.0.1:"), ready)
    return ready, errlog


class BusyGuest(unittest.TestCase):
    @unittest.skipUnless(fifo_allowed(), "this host refuses SCHED_FIFO: no real-time servo to guard")
    @unittest.skipUnless(os.path.isfile(BOOT_IMAGE) and shutil.which("qemu-system-arm"),
                         "no QEMU bootloader image or qemu-system-arm")
    def test_servos_in_the_update_bootloader_sleep_and_answer(self):
        """The micro:bit bootloader sleeps between bytes (docs/update.md §6,
        km_bootb_wait): in update mode its guests do not busy-loop, so they
        keep SCHED_FIFO, and each answers a ping there and after START."""
        ready, errlog = start_boot_bus(self, "1,2,3")
        errlog.seek(0)
        pids = {int(i): int(pid) for i, pid in re.findall(r"servo id (\d+): pid (\d+) on port",
                                                          errlog.read())}
        self.assertEqual({policy for pid in pids.values() for policy in policies(pid)},
                         {os.SCHED_FIFO})
        sock = socket.create_connection(("127.0.0.1", int(ready.rsplit(":", 1)[1])), timeout=5)
        self.addCleanup(sock.close)
        sock.sendall(ENTER)
        time.sleep(0.5)
        sock.sendall(ENTER)  # a broadcast has no answer: sent twice, as a master would
        time.sleep(3.0)      # the guard judges every 50 ms over the last 0.2 s
        errlog.seek(0)
        busy = re.findall(r"servo id (\d+): its guest busy-loops", errlog.read())
        self.assertEqual(busy, [])
        self.assertEqual({policy for pid in pids.values() for policy in policies(pid)},
                         {os.SCHED_FIFO})
        for dev_id in (1, 2, 3):  # the bootloader answers a ping
            self.assertTrue(ping(sock, dev_id, 5.0), "servo %d silent in its bootloader" % dev_id)
        sock.sendall(START)  # back to the application
        for dev_id in (1, 2, 3):
            deadline = time.monotonic() + 20
            while not ping(sock, dev_id, 0.5):
                self.assertLess(time.monotonic(), deadline, "servo %d silent after START" % dev_id)

class BootPriority(unittest.TestCase):
    """Servos of an image with the update bootloader, which polls its UART,
    run one priority below every other servo: while two of them busy-loop at
    the same priority as the rest, every other real-time servo on a
    two-core host waits until the CPU guard acts (a conformance load run on
    host-sim lost a super-ID round that way to another bus's two QEMU
    servos entering the bootloader); one below, a servo that has to answer
    takes the core from them at once."""

    @unittest.skipUnless(fifo_allowed(), "this host refuses SCHED_FIFO: no priorities to compare")
    @unittest.skipUnless(os.path.isfile(BOOT_IMAGE) and shutil.which("qemu-system-arm"),
                         "no QEMU bootloader image or qemu-system-arm")
    def test_an_image_with_the_polling_bootloader_runs_below_other_servos(self):
        ready, errlog = start_boot_bus(self, "1")
        errlog.seek(0)
        err = errlog.read()
        pids = [int(pid) for pid in re.findall(r"servo id \d+: pid (\d+) on port", err)]
        self.assertEqual(len(pids), 1, err)
        self.assertEqual((os.sched_getscheduler(pids[0]), os.sched_getparam(pids[0]).sched_priority),
                         (os.SCHED_FIFO, 9))
        self.assertIn("servo-bus: the image holds the update bootloader (it polls its UART): servos "
                      "at priority 9, below other servos\n", err)


# A guest that polls: told it runs, it spins (at most SPIN_S, should the guard
# never act) and then sleeps.
SPINNER = ("import sys, time\n"
           "sys.stdout.write('x'); sys.stdout.flush()\n"
           "end = time.monotonic() + %r\n"
           "while time.monotonic() < end: pass\n"
           "time.sleep(30)\n")
SPIN_S = 5.0
# The conformance timeout (tests/conformance/conformance.py --timeout): a guard
# slower than this lets a busy guest on the host cost another bus an answer.
GUARD_BOUND_S = 0.5


class _Servo:
    def __init__(self, dev_id, proc):
        self.id, self.proc = dev_id, proc


class GuardLatency(unittest.TestCase):
    """The guard puts a busy-looping servo to plain scheduling within the
    conformance timeout: while such guests hold the cores at SCHED_FIFO,
    every other real-time servo on the host waits, another bus's too (the
    conformance load on host-sim lost a super-ID round for 1.7-2.0 s to two
    QEMU servos of another bus entering the update bootloader)."""

    @unittest.skipUnless(fifo_allowed(), "this host refuses SCHED_FIFO: no real-time servo to guard")
    def test_a_busy_guest_goes_plain_within_the_conformance_timeout(self):
        import test_servo_bus
        mod = test_servo_bus.load_launcher_module()
        logged = []
        mod.log = logged.append
        spinner = subprocess.Popen([sys.executable, "-c", SPINNER % SPIN_S], stdout=subprocess.PIPE,
                                   preexec_fn=lambda: os.sched_setscheduler(
                                       0, os.SCHED_FIFO, os.sched_param(mod.REALTIME_PRIORITY)))
        self.addCleanup(spinner.stdout.close)
        self.addCleanup(spinner.wait, 10)
        self.addCleanup(spinner.kill)
        # the hub's priority, above the spinner, as servo-bus runs its guard
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(mod.HUB_PRIORITY))
        self.addCleanup(os.sched_setscheduler, 0, os.SCHED_OTHER, os.sched_param(0))
        guard = mod.CpuGuard([_Servo(7, spinner)])
        guard.tick()  # the bus watches its servos from their start
        self.assertEqual(spinner.stdout.read(1), b"x")
        start = time.monotonic()
        while spinner.pid not in guard.plain and time.monotonic() - start < SPIN_S:
            time.sleep(0.01)
            guard.tick()
        took = time.monotonic() - start
        self.assertIn(spinner.pid, guard.plain, "the guard never acted: %r" % logged)
        self.assertEqual(policies(spinner.pid), {os.SCHED_OTHER})
        self.assertLess(took, GUARD_BOUND_S, "a busy guest held its core for %.2f s" % took)
        self.assertRegex(logged[0], r"servo id 7: its guest busy-loops \(\d+ % of a core\): plain "
                         r"scheduling for it from now on")


if __name__ == "__main__":
    unittest.main()
