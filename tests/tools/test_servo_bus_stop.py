# SPDX-License-Identifier: Apache-2.0
"""sim/bus/servo-bus starts and stops cleanly (issue 11 item 4): Ctrl-C at
random moments of start-up leaves no servo process behind, checked by PID
(tests/tools/ctrl_c_check.py: 20 runs on host-sim and 20 on QEMU when its
image and qemu-system-arm are there, about 15 s); a signal that comes at
the last moments of start-up, after the last servo answered, ends it
without "ready" (issue 18 item 10: placed there by a profile hook on the
real script, once before the final check and once inside it while the
signals are held back); a Ctrl-C that also reaches the board query (cmake)
stops start-up cleanly; host-sim servos start while every port servo-bus
lets go of is taken at once by someone else; a servo-bus killed with
SIGKILL takes its servos with it (PR_SET_PDEATHSIG); relaunching with
--flash-dir after an ID change finds the servo at its stored ID; and the
start-up refusals are one line each: a missing qemu-system-arm (naming the
Debian package), an unknown backend, a bad --baud."""
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

from test_kmx import REPO, host_sim_image  # noqa: E402
import simbus  # noqa: E402  (sim/bus: the boards' builds, found as servo-bus finds them)
from test_kmx_cli import kmx  # noqa: E402

CHECK = os.path.join(REPO, "tests", "tools", "ctrl_c_check.py")
SERVO_BUS = os.path.join(REPO, "sim", "bus", "servo-bus")
QEMU_IMAGE = simbus.default_image("qemu")[0]


def alive(pid):
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().split(") ", 1)[1][0] != "Z"
    except OSError:
        return False


class CtrlC(unittest.TestCase):
    def run_check(self, backend, runs):
        r = subprocess.run([sys.executable, CHECK, "--backend", backend, "--runs", str(runs)],
                           capture_output=True, text=True, timeout=300)
        print(r.stdout.splitlines()[-1] if r.stdout else r.stderr, file=sys.stderr)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertRegex(r.stdout, r"%d runs, 0 left processes behind" % runs)

    def test_ctrl_c_during_start_up_host_sim(self):
        host_sim_image()
        self.run_check("host-sim", 20)

    @unittest.skipUnless(os.path.isfile(QEMU_IMAGE) and shutil.which("qemu-system-arm"),
                         "no QEMU image or qemu-system-arm")
    def test_ctrl_c_during_start_up_qemu(self):
        self.run_check("qemu", 20)


# Runs sim/bus/servo-bus as __main__, unchanged, and sends itself SIGNAL at one
# point of its start-up, found by a profile hook: "bus" when the Bus object
# is built (after the servos answered, just before the ready line), "held"
# right after announce_ready() blocked the stop signals (the kernel then
# keeps the signal pending). Prints "sent" on stderr when it sent it.
AT_LAST_MOMENT = r"""
import os, runpy, signal, sys
script, where, signame = sys.argv[1:4]
sig = getattr(signal, signame)
def hook(frame, event, arg):
    code = frame.f_code
    if where == "bus" and event == "return" and code.co_filename == script \
            and code.co_name == "__init__" and type(frame.f_locals.get("self")).__name__ == "Bus":
        fire()
    # signal.pthread_sigmask is signal.py's wrapper: its return, called
    # from announce_ready, the first time (the block)
    if where == "held" and event == "return" and code.co_name == "pthread_sigmask" \
            and frame.f_back.f_code.co_filename == script \
            and frame.f_back.f_code.co_name == "announce_ready":
        fire()
def fire():
    sys.setprofile(None)
    os.kill(os.getpid(), sig)
    print("sent", file=sys.stderr, flush=True)
sys.argv = [script] + sys.argv[4:]
sys.setprofile(hook)
runpy.run_path(script, run_name="__main__")
"""


class SignalBeforeReady(unittest.TestCase):
    """A stop signal that comes before the ready line ends start-up: no
    "ready", exit 0, every servo process gone (issue 18 item 10)."""

    def run_until_signal(self, where, signame):
        host_sim_image()
        p = subprocess.Popen([sys.executable, "-c", AT_LAST_MOMENT, os.path.realpath(SERVO_BUS), where,
                              signame, "--ids", "1,2", "--port", "0", "--backend", "host-sim"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        ready = p.stdout.readline()  # "" at exit; after a ready line the bus stays up: stop it
        if ready:
            p.terminate()
        out, err = p.communicate(timeout=60)
        pids = [int(pid) for pid in re.findall(r"pid (\d+) on port", err)]
        self.assertEqual(len(pids), 2, err)
        self.assertIn("\nsent\n", err, "the hook never sent %s" % signame)
        self.assertEqual((p.returncode, ready + out), (0, ""), err)
        self.assertEqual(err.splitlines()[-1], "servo-bus: stopping")
        self.assertNotIn("Traceback", err)
        self.assertEqual([pid for pid in pids if alive(pid)], [])

    def test_sigint_after_the_last_servo_answered(self):
        self.run_until_signal("bus", "SIGINT")

    def test_sigterm_after_the_last_servo_answered(self):
        self.run_until_signal("bus", "SIGTERM")

    def test_sigint_while_the_final_check_holds_signals_back(self):
        self.run_until_signal("held", "SIGINT")


# A cmake for servo-bus's board discovery (sim/bus/simbus.py) that is caught
# by a terminal's Ctrl-C to servo-bus's process group before it left that
# group: it sends SIGINT to servo-bus and to itself (what the group's signal
# does to both at once), then runs the real cmake.
CMAKE_CAUGHT_BY_CTRL_C = """#!%s
import os, signal, sys
os.kill(os.getppid(), signal.SIGINT)
os.kill(os.getpid(), signal.SIGINT)
os.execv(%r, [%r] + sys.argv[1:])
"""


class SignalDuringBoardDiscovery(unittest.TestCase):
    """A Ctrl-C that reaches servo-bus's board query (cmake) too, in the
    moment between its fork and its own session, stops start-up cleanly
    (exit 0, "stopping"), not as a failed discovery (exit 2): one run in
    five of ctrl_c_check.py on a loaded host failed so."""

    def test_ctrl_c_caught_by_the_board_query(self):
        host_sim_image()
        with tempfile.TemporaryDirectory() as d:
            real = shutil.which("cmake")
            fake = os.path.join(d, "cmake")
            with open(fake, "w") as f:
                f.write(CMAKE_CAUGHT_BY_CTRL_C % (sys.executable, real, real))
            os.chmod(fake, 0o755)
            env = dict(os.environ, PATH=d + os.pathsep + os.environ["PATH"])
            r = subprocess.run([sys.executable, SERVO_BUS, "--ids", "1", "--port", "0", "--backend", "host-sim"],
                               capture_output=True, text=True, timeout=60, env=env)
        self.assertEqual((r.returncode, r.stdout), (0, ""), r.stderr)
        self.assertEqual(r.stderr.splitlines()[-1], "servo-bus: stopping", r.stderr)
        self.assertNotIn("pid", r.stderr)  # stopped before any servo started


# Runs sim/bus/servo-bus as __main__, unchanged, in a world where every port
# it lets go of is taken at once by another process: a socket it bound to
# port 0 (the kernel's choice) and closes is followed, in the same instant,
# by a listener of someone else's on that port, unless another process (a
# servo) still holds it. Says "took port N" on stderr.
PORTS_TAKEN_AT_ONCE = r"""
import runpy, socket, sys
script = sys.argv[1]
squatters, chosen_by = [], {}  # id(socket) -> the address the kernel chose
bind, close = socket.socket.bind, socket.socket.close
def bind_noting(self, address):
    bind(self, address)
    if isinstance(address, tuple) and address[1] == 0:
        chosen_by[id(self)] = self.getsockname()
def close_and_take(self):
    chosen = chosen_by.pop(id(self), None)
    close(self)
    if chosen is not None:
        squatter = socket.socket()
        try:
            bind(squatter, chosen)  # refused while another holds the port (a servo)
        except OSError:
            return
        squatter.listen(1)
        squatters.append(squatter)
        print("took port %d" % chosen[1], file=sys.stderr, flush=True)
socket.socket.bind, socket.socket.close = bind_noting, close_and_take
sys.argv = [script] + sys.argv[2:]
runpy.run_path(script, run_name="__main__")
"""


class PortTakenMeanwhile(unittest.TestCase):
    """A servo listens on a port no other process can take first (host-sim
    binds one itself, QEMU inherits a listening socket): servo-bus once chose
    each servo's port (bind to port 0, close) and the servo bound it later,
    and a port taken in between made that servo exit 1 at start-up."""

    def start_with_released_ports_taken(self, backend):
        p = subprocess.Popen([sys.executable, "-c", PORTS_TAKEN_AT_ONCE, os.path.realpath(SERVO_BUS),
                              "--ids", "1,2", "--port", "0", "--backend", backend],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            ready = p.stdout.readline()
            answered = ready.startswith("ready ") and kmx("tcp:" + ready.split()[1], "ping", "2").returncode
        finally:
            p.terminate()
            _, err = p.communicate(timeout=30)
        self.assertTrue(ready.startswith("ready "), err)
        self.assertEqual(answered, 0, err)
        self.assertEqual(p.returncode, 0, err)

    def test_host_sim_bus_starts_when_released_ports_are_taken(self):
        host_sim_image()
        self.start_with_released_ports_taken("host-sim")

    @unittest.skipUnless(os.path.isfile(QEMU_IMAGE) and shutil.which("qemu-system-arm"),
                         "no QEMU image or qemu-system-arm")
    def test_qemu_bus_starts_when_released_ports_are_taken(self):
        self.start_with_released_ports_taken("qemu")


class Lifecycle(unittest.TestCase):
    def start(self, *args):
        p = subprocess.Popen([sys.executable, SERVO_BUS, "--port", "0", "--backend", "host-sim", *args],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        def cleanup():
            if p.poll() is None:
                p.kill()
            p.wait()
            p.stdout.close()
            p.stderr.close()
        self.addCleanup(cleanup)
        line = p.stdout.readline()
        self.assertTrue(line.startswith("ready "), line)
        return p, "tcp:" + line.split()[1]

    def test_sigkill_takes_the_servos_along(self):
        host_sim_image()
        p, _ = self.start("--ids", "1,2")
        pids = []
        while len(pids) < 2:
            m = re.search(r"pid (\d+) on port", p.stderr.readline())
            if m:
                pids.append(int(m.group(1)))
        self.assertTrue(all(alive(pid) for pid in pids))
        p.kill()
        p.wait()
        deadline = time.monotonic() + 3
        while any(alive(pid) for pid in pids) and time.monotonic() < deadline:
            time.sleep(0.05)
        self.assertEqual([pid for pid in pids if alive(pid)], [])

    def test_flash_dir_keeps_ids_across_relaunch(self):
        host_sim_image()
        with tempfile.TemporaryDirectory() as d:
            p, spec = self.start("--ids", "1", "--flash-dir", d)
            r = kmx(spec, "set-id", "1", "7")
            self.assertEqual(r.returncode, 0, r.stderr)
            p.terminate()
            p.wait(timeout=10)
            # the same command again: servo-1.flash now holds ID 7, and the
            # servo is found there (super-ID ping), not written back to 1
            p, spec = self.start("--ids", "1", "--flash-dir", d)
            r = kmx(spec, "ping", "7")
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertEqual(kmx(spec, "ping", "1").returncode, 1)
            p.terminate()
            _, err = p.communicate(timeout=10)
            self.assertIn("servo id 1 (servo-1.flash): kept its stored ID 7", err)
            p.stdout.close()

    def test_refusals_are_one_line(self):
        env = dict(os.environ, PATH="/nonexistent")
        r = subprocess.run([sys.executable, SERVO_BUS, "--ids", "1", "--port", "0", "--backend", "qemu",
                            "--image", SERVO_BUS], capture_output=True, text=True, timeout=20, env=env)
        self.assertEqual((r.returncode, r.stderr), (2, "servo-bus: qemu-system-arm not found: apt-get install "
                                                       "qemu-system-arm (Debian), or use --backend host-sim\n"))
        r = subprocess.run([sys.executable, SERVO_BUS, "--ids", "1", "--port", "0", "--backend", "qemuu"],
                           capture_output=True, text=True, timeout=20)
        self.assertEqual(r.returncode, 2)
        self.assertEqual(r.stderr.splitlines()[-1],
                         "servo-bus: error: argument --backend: invalid choice: 'qemuu' (choose from "
                         "'g031', 'host-sim', 'qemu')")


if __name__ == "__main__":
    unittest.main()


class OneLineMessages(unittest.TestCase):
    """The launchers' own refusals and goodbyes: one line, no traceback."""

    def test_servo_session_tcp_without_port(self):
        r = subprocess.run([os.path.join(REPO, "tools", "servo-session"), "--tcp", "127.0.0.1"],
                           capture_output=True, text=True, timeout=20)
        self.assertEqual((r.returncode, r.stderr), (1, "servo-session: bus 'tcp:127.0.0.1': tcp wants HOST:PORT, "
                                                       "e.g. tcp:127.0.0.1:7000\n"))

    def test_servo_demo_bad_options(self):
        demo = os.path.join(REPO, "tools", "servo-demo")
        for argv, msg in ((["--backend", "qemuu"], "servo-demo: unknown backend 'qemuu': qemu or host-sim\n"),
                          (["--port"], "servo-demo: --port needs a value (0: a free port)\n"),
                          (["--port", "x7"], "servo-demo: --port 'x7' is not a port number (0: a free port)\n")):
            r = subprocess.run([demo, *argv], capture_output=True, text=True, timeout=20)
            self.assertEqual((r.returncode, r.stderr), (2, msg))

    def test_servo_bus_ctrl_c_goodbye(self):
        host_sim_image()
        p = subprocess.Popen([sys.executable, SERVO_BUS, "--ids", "1", "--port", "0", "--backend", "host-sim"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.assertTrue(p.stdout.readline().startswith("ready "))
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=20)
        self.assertEqual((p.returncode, out), (0, ""))
        self.assertEqual(err.splitlines()[-1], "servo-bus: stopping")
        self.assertNotIn("Traceback", err)
