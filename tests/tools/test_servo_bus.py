# SPDX-License-Identifier: Apache-2.0
"""sim/bus/servo-bus against tests/tools/fake_servo.py (a stand-in for the
host-sim program, speaking its command-line contract): provisioning of IDs,
the shared-bus relay, missing images, child death and stopping, and the
per-servo options (--gap-floor-us, --build-dir). No QEMU."""
import contextlib
import importlib.machinery
import importlib.util
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest

HERE = os.path.dirname(os.path.realpath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
LAUNCHER = os.path.join(REPO, "sim", "bus", "servo-bus")
FAKE = os.path.join(HERE, "fake_servo.py")
from kmx import frame as kmframe  # noqa: E402  (docs/architecture.md "The folders": PYTHONPATH)


def pid_alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie still "exists": look at its state
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False


@contextlib.contextmanager
def build_env(**values):
    """The environment without any KM_BUILD_DIR_* but these, for the block."""
    saved = {k: v for k, v in os.environ.items() if k.startswith("KM_BUILD_DIR_")}
    for k in saved:
        del os.environ[k]
    os.environ.update(values)
    try:
        yield
    finally:
        for k in values:
            os.environ.pop(k, None)
        os.environ.update(saved)


def load_launcher_module():
    loader = importlib.machinery.SourceFileLoader("servo_bus", LAUNCHER)
    spec = importlib.util.spec_from_loader("servo_bus", loader)
    mod = importlib.util.module_from_spec(spec)
    loader.exec_module(mod)
    return mod


# A host-sim stand-in that also takes --gap-floor-us: logs its argv (one file
# per process) and runs fake_servo.py without the option.
ARGV_LOGGER = """#!%s
import os, subprocess, sys
argv = sys.argv[1:]
with open(os.path.join(os.environ["FAKE_SERVO_LOG_DIR"], "argv-%%d.txt" %% os.getpid()), "w") as f:
    f.write("\\n".join(argv))
if "--gap-floor-us" in argv:
    i = argv.index("--gap-floor-us")
    del argv[i:i + 2]
os.execv(sys.executable, [sys.executable, %r] + argv)
"""


class Launcher:
    def __init__(self, ids, env=None, extra=(), image=FAKE):
        self.logdir = tempfile.mkdtemp(prefix="fake-servo-")
        e = dict(os.environ, FAKE_SERVO_LOG_DIR=self.logdir)
        e.update(env or {})
        self.proc = subprocess.Popen(
            [sys.executable, LAUNCHER, "--ids", ",".join(map(str, ids)), "--port", "0",
             "--backend", "host-sim", "--image", image, *extra],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=e)

    def wait_ready(self):
        line = self.proc.stdout.readline()
        if not line.startswith("ready "):
            self.proc.kill()
            raise AssertionError("no ready line: %r, stderr: %s"
                                 % (line, self.proc.stderr.read()))
        host, port = line.split()[1].split(":")
        return line, (host, int(port))

    def pid_of(self, dev_id):
        with open(os.path.join(self.logdir, "id%d.pid" % dev_id)) as f:
            return int(f.read())

    def heard_by(self, dev_id):
        with open(os.path.join(self.logdir, "rx-%d.bin" % self.pid_of(dev_id)), "rb") as f:
            return f.read()

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        out, err = self.proc.communicate(timeout=10)
        return self.proc.returncode, out, err


def exchange(sock, frame, timeout=0.5, settle=0.0):
    """Send a frame; collect response frames until timeout passes with no data."""
    sock.sendall(frame)
    parser = kmframe.Parser()
    frames = []
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        sock.settimeout(max(0.01, end - time.monotonic()))
        try:
            data = sock.recv(4096)
        except socket.timeout:
            break
        if not data:
            break
        frames += parser.feed(data)
        if frames and not settle:
            break
    return frames


class ServoBus(unittest.TestCase):
    def test_missing_image_names_the_preset(self):
        for backend, preset in (("qemu", "cmake --preset qemu"),
                                ("host-sim", "cmake --preset host-sim")):
            r = subprocess.run([sys.executable, LAUNCHER, "--ids", "1", "--port", "0",
                                "--backend", backend, "--image", "/nonexistent/servo.elf"],
                               capture_output=True, text=True, timeout=10)
            self.assertEqual(r.returncode, 2)
            self.assertEqual(r.stdout, "")
            self.assertIn("/nonexistent/servo.elf", r.stderr)
            self.assertIn(preset, r.stderr)

    def test_provisions_ids_and_relays_the_bus(self):
        ln = Launcher([1, 2, 3], env={"FAKE_SERVO_BOOT_DELAY": "0.3"})
        try:
            line, addr = ln.wait_ready()
            self.assertEqual(line, "ready %s:%d\n" % addr)
            with socket.create_connection(addr) as s:
                for dev_id in (1, 2, 3):
                    got = exchange(s, kmframe.ping(dev_id))
                    self.assertEqual([(f.id, f.status) for f in got], [(dev_id, 0)])
                    got = exchange(s, kmframe.read(dev_id, kmframe.REG_ID))
                    self.assertEqual([(f.id, f.params) for f in got], [(dev_id, bytes([dev_id]))])
                # nobody is left on the default ID
                self.assertEqual(exchange(s, kmframe.ping(0), timeout=0.3), [])
                # super ID: everyone answers, each on the client's wire
                got = exchange(s, kmframe.ping(kmframe.ID_SUPER), timeout=0.5, settle=1)
                self.assertEqual(sorted(f.id for f in got), [1, 2, 3])
            # what servo 1 said on the bus was heard by servos 2 and 3, not echoed to 1
            answer1 = kmframe.encode_status(1, 0)
            self.assertIn(answer1, ln.heard_by(2))
            self.assertIn(answer1, ln.heard_by(3))
            self.assertNotIn(answer1, ln.heard_by(1))
            # the client's bytes reached every servo
            for dev_id in (1, 2, 3):
                self.assertIn(kmframe.ping(2), ln.heard_by(dev_id))
            # provisioning spoke to each servo alone: servo 2 never heard
            # servo 1's write of its ID
            self.assertNotIn(kmframe.write(0, kmframe.REG_ID, b"\x01"), ln.heard_by(2))
            self.assertIn(kmframe.write(0, kmframe.REG_ID, b"\x02"), ln.heard_by(2))
            # the provisioning transcript, alone with each servo: ping 0 until
            # it answers, write 0x0F, then a confirming ping on the new ID
            for dev_id in (1, 2, 3):
                rx = ln.heard_by(dev_id)
                self.assertTrue(rx.startswith(kmframe.ping(0)))
                while rx.startswith(kmframe.ping(0)):
                    rx = rx[len(kmframe.ping(0)):]
                confirm = kmframe.write(0, kmframe.REG_ID, bytes([dev_id])) + kmframe.ping(dev_id)
                self.assertTrue(rx.startswith(confirm), rx.hex())
            # a second client after the first disconnects
            with socket.create_connection(addr) as s:
                got = exchange(s, kmframe.ping(3))
                self.assertEqual([f.id for f in got], [3])
            pids = [ln.pid_of(i) for i in (1, 2, 3)]
        finally:
            rc, out, err = ln.stop()
        self.assertEqual(rc, 0, err)
        self.assertEqual(out, "")  # nothing on stdout after the ready line
        time.sleep(0.1)
        for pid in pids:
            self.assertFalse(pid_alive(pid), "servo pid %d still running" % pid)

    def test_a_client_gone_before_the_hub_saw_it_leaves_the_bus_free(self):
        """A client that connected and left while servo-bus was not running
        (a loaded host) does not hold the bus against the next one: the hub
        once accepted it, then the next client before reading the first
        one's end, and told the next one the bus was busy."""
        launcher = Launcher([1])
        try:
            _, addr = launcher.wait_ready()
            os.kill(launcher.proc.pid, signal.SIGSTOP)  # the hub does not run meanwhile
            try:
                socket.create_connection(addr, timeout=5).close()
                second = socket.create_connection(addr, timeout=5)
            finally:
                os.kill(launcher.proc.pid, signal.SIGCONT)
            with second:
                frames = exchange(second, kmframe.ping(1), timeout=5)
        finally:
            code, _, err = launcher.stop()
        self.assertEqual([f.id for f in frames], [1], err)
        self.assertIn("client disconnected", err)

    def test_flash_dir_keeps_ids_across_runs(self):
        with tempfile.TemporaryDirectory() as flash_dir:
            for run in (1, 2):
                ln = Launcher([8, 9], extra=("--flash-dir", flash_dir))
                try:
                    _, addr = ln.wait_ready()
                    with socket.create_connection(addr) as s:
                        self.assertEqual([f.id for f in exchange(s, kmframe.ping(9))], [9])
                    heard = ln.heard_by(9)
                finally:
                    rc, _, err = ln.stop()
                self.assertEqual(rc, 0, err)
                wrote = kmframe.write(0, kmframe.REG_ID, b"\x09") in heard
                # first run: fresh servo, written; second: already ID 9, not written
                self.assertEqual(wrote, run == 1)
            self.assertTrue(os.path.isfile(os.path.join(flash_dir, "servo-9.flash")))

    def test_child_killed_by_signal_is_reported(self):
        ln = Launcher([3])
        ln.wait_ready()
        os.kill(ln.pid_of(3), signal.SIGKILL)
        ln.proc.wait(timeout=10)
        rc, _, err = ln.stop()
        self.assertEqual(rc, 1)
        self.assertRegex(err, r"servo id 3 \(pid \d+\) killed by signal 9")

    def test_child_death_is_reported(self):
        ln = Launcher([4, 5], env={"FAKE_SERVO_EXIT": "5:0.5:7"})
        ln.wait_ready()
        survivor = ln.pid_of(4)
        try:
            ln.proc.wait(timeout=10)
        finally:
            rc, _, err = ln.stop()
        self.assertNotEqual(rc, 0)
        self.assertRegex(err, r"servo id 5 \(pid \d+\) exited with code 7")
        time.sleep(0.1)
        self.assertFalse(pid_alive(survivor))

    def test_death_during_provisioning_is_reported(self):
        ln = Launcher([6], env={"FAKE_SERVO_EXIT": "0:0:3"})
        rc, out, err = ln.stop() if ln.proc.wait(timeout=10) is not None else (None, "", "")
        self.assertEqual(rc, 1)
        self.assertEqual(out, "")
        self.assertRegex(err, r"servo id 6 \(pid \d+\) exited with code 3")


class GapFloorOption(unittest.TestCase):
    def test_help_says_what_and_the_default(self):
        r = subprocess.run([sys.executable, LAUNCHER, "--help"], capture_output=True, text=True,
                           timeout=10)
        self.assertEqual(r.returncode, 0)
        self.assertIn("--gap-floor-us N", r.stdout)
        self.assertIn("20000", r.stdout)
        self.assertIn("0 = that real rule", " ".join(r.stdout.split()))

    def test_bad_values_are_usage_errors(self):
        for bad in ("-1", "abc", "4294967296"):
            r = subprocess.run([sys.executable, LAUNCHER, "--ids", "1", "--port", "0",
                                "--backend", "host-sim", "--image", FAKE, "--gap-floor-us", bad],
                               capture_output=True, text=True, timeout=10)
            self.assertEqual(r.returncode, 2, bad)

    def test_argv_per_backend(self):
        sb = load_launcher_module()
        host = sb.servo_argv("host-sim", "/img", 7001, "/f", None, 0)
        self.assertEqual(host[-2:], ["--gap-floor-us", "0"])
        self.assertNotIn("--gap-floor-us", sb.servo_argv("host-sim", "/img", 7001, "/f", None))
        qemu = sb.servo_argv("qemu", "/img.elf", 7001, "/f", None, 1500)
        loaders = [qemu[i + 1] for i, a in enumerate(qemu) if a == "-device"]
        # magic, then the values, at the linker-placed words (nrf51822.ld
        # .km_config): with the magic every word is in force, so the product
        # word is written too (0 = pot)
        self.assertEqual(loaders, ["loader,addr=0x20000000,data=0x4b4d4746,data-len=4",
                                   "loader,addr=0x20000004,data=0x000005dc,data-len=4",
                                   "loader,addr=0x20000008,data=0x00000000,data-len=4",
                                   "loader,addr=0x2000000c,data=0x00000000,data-len=4"])
        self.assertNotIn("-device", sb.servo_argv("qemu", "/img.elf", 7001, "/f", None))

    def test_product_option(self):
        sb = load_launcher_module()
        host = sb.servo_argv("host-sim", "/img", 7001, "/f", None, None, "encoder")
        self.assertEqual(host[-2:], ["--product", "encoder"])
        self.assertNotIn("--product", sb.servo_argv("host-sim", "/img", 7001, "/f", None, 0))
        qemu = sb.servo_argv("qemu", "/img.elf", 7001, "/f", None, None, "encoder")
        loaders = [qemu[i + 1] for i, a in enumerate(qemu) if a == "-device"]
        # product alone: the gap floor word gets the servos' default (20000)
        self.assertEqual(loaders, ["loader,addr=0x20000000,data=0x4b4d4746,data-len=4",
                                   "loader,addr=0x20000004,data=0x00004e20,data-len=4",
                                   "loader,addr=0x20000008,data=0x00000001,data-len=4",
                                   "loader,addr=0x2000000c,data=0x00000000,data-len=4"])
        r = subprocess.run([sys.executable, LAUNCHER, "--ids", "1", "--port", "0",
                            "--backend", "host-sim", "--image", FAKE, "--product", "stepper"],
                           capture_output=True, text=True, timeout=10)
        self.assertEqual(r.returncode, 2)

    def test_slot_floor_and_qemu_args(self):
        """--slot-floor-us: host-sim's argument, QEMU's word at 0x2000000C
        (docs/protocol-decisions.md "Answer slots on emulated buses");
        --qemu-arg: appended to QEMU's command line in order."""
        sb = load_launcher_module()
        host = sb.servo_argv("host-sim", "/img", 7001, "/f", None, None, None, None, (), 3000)
        self.assertEqual(host[-2:], ["--slot-floor-us", "3000"])
        self.assertNotIn("--slot-floor-us", sb.servo_argv("host-sim", "/img", 7001, "/f", None))
        qemu = sb.servo_argv("qemu", "/img.elf", 7001, "/f", None, None, None, None,
                             ("-icount", "shift=4"), 3000)
        loaders = [qemu[i + 1] for i, a in enumerate(qemu) if a == "-device"]
        self.assertEqual(loaders, ["loader,addr=0x20000000,data=0x4b4d4746,data-len=4",
                                   "loader,addr=0x20000004,data=0x00004e20,data-len=4",
                                   "loader,addr=0x20000008,data=0x00000000,data-len=4",
                                   "loader,addr=0x2000000c,data=0x00000bb8,data-len=4"])
        self.assertEqual(qemu[-2:], ["-icount", "shift=4"])
        for extra in (["--slot-floor-us", "-5"], ["--qemu-arg=-icount"]):
            r = subprocess.run([sys.executable, LAUNCHER, "--ids", "1", "--port", "0",
                                "--backend", "host-sim", "--image", FAKE] + extra,
                               capture_output=True, text=True, timeout=10)
            self.assertEqual(r.returncode, 2, extra)

    def test_build_dir_option_and_environment(self):
        sb = load_launcher_module()
        self.assertEqual(sb.default_image("host-sim", "build/x"),
                         os.path.join(REPO, "build/x/boards/host-sim/km-servo-host-sim"))
        with build_env(KM_BUILD_DIR_qemu_microbit="build/q2"):
            self.assertEqual(sb.default_image("qemu"), os.path.join(
                REPO, "build/q2/boards/qemu-microbit/km-servo-qemu-microbit.elf"))
        r = subprocess.run([sys.executable, LAUNCHER, "--ids", "1", "--port", "0",
                            "--backend", "host-sim", "--build-dir", "/nonexistent-build"],
                           capture_output=True, text=True, timeout=10)
        self.assertEqual(r.returncode, 2)
        self.assertIn("/nonexistent-build/boards/host-sim/km-servo-host-sim", r.stderr)

    def test_build_found_by_board_discovery(self):
        """Issue 19: the image is the one of the board whose board.cmake names
        the backend, in the binaryDir of the preset that builds it; a missing
        build says the commands that make it; a backend no board names is refused."""
        import simbus
        with open(os.path.join(REPO, "CMakePresets.json")) as f:
            presets = {p["name"]: p for p in json.load(f)["configurePresets"]}
        with build_env():
            for backend, preset, image in (("qemu", "qemu", "boards/qemu-microbit/km-servo-qemu-microbit.elf"),
                                           ("host-sim", "host-sim", "boards/host-sim/km-servo-host-sim")):
                tree = presets[preset]["binaryDir"].replace("${sourceDir}", REPO)
                self.assertEqual(simbus.default_image(backend), (
                    os.path.join(tree, image), "cmake --preset %s && cmake --build --preset %s" % (preset, preset)))
        with build_env(KM_BUILD_DIR_host_sim="/nonexistent-build"):
            r = subprocess.run([sys.executable, LAUNCHER, "--ids", "1", "--port", "0", "--backend", "host-sim"],
                               capture_output=True, text=True, timeout=10)
        self.assertEqual((r.returncode, r.stderr), (2, (
            "servo-bus: no host-sim image at /nonexistent-build/boards/host-sim/km-servo-host-sim; build it "
            "first: cmake -S %s -B /nonexistent-build -DKM_BOARD=host-sim && cmake --build /nonexistent-build\n"
            % REPO)))
        with self.assertRaisesRegex(simbus.BuildMissing, "no board names the bus backend 'nothing'"):
            simbus.default_image("nothing")

    def test_every_servo_gets_the_floor(self):
        with tempfile.TemporaryDirectory() as tmp:
            image = os.path.join(tmp, "servo")
            with open(image, "w") as f:
                f.write(ARGV_LOGGER % (sys.executable, FAKE))
            os.chmod(image, 0o755)
            ln = Launcher([1, 2], image=image, extra=("--gap-floor-us", "0"))
            try:
                _, addr = ln.wait_ready()
                with socket.create_connection(addr) as s:
                    self.assertEqual([f.id for f in exchange(s, kmframe.ping(2))], [2])
            finally:
                rc, _, err = ln.stop()
            self.assertEqual(rc, 0, err)
            logs = [n for n in os.listdir(ln.logdir) if n.startswith("argv-")]
            self.assertEqual(len(logs), 2)
            for name in logs:
                with open(os.path.join(ln.logdir, name)) as f:
                    argv = f.read().split("\n")
                self.assertEqual(argv[argv.index("--gap-floor-us") + 1], "0")
            # without the option nothing extra is passed (fake_servo.py would refuse it)
            ln = Launcher([3])
            try:
                ln.wait_ready()
            finally:
                rc, _, err = ln.stop()
            self.assertEqual(rc, 0, err)


if __name__ == "__main__":
    unittest.main()
