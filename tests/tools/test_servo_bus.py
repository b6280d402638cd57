"""tools/servo-bus against tests/tools/fake_servo.py (a stand-in for the
host-sim program, speaking its command-line contract): provisioning of IDs,
the shared-bus relay, missing images, child death and stopping. No QEMU."""
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
LAUNCHER = os.path.join(REPO, "tools", "servo-bus")
FAKE = os.path.join(HERE, "fake_servo.py")
sys.path.insert(0, os.path.join(REPO, "tools"))
import kmbus  # noqa: E402


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


class Launcher:
    def __init__(self, ids, env=None, extra=()):
        self.logdir = tempfile.mkdtemp(prefix="fake-servo-")
        e = dict(os.environ, FAKE_SERVO_LOG_DIR=self.logdir)
        e.update(env or {})
        self.proc = subprocess.Popen(
            [sys.executable, LAUNCHER, "--ids", ",".join(map(str, ids)), "--port", "0",
             "--backend", "host-sim", "--image", FAKE, *extra],
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
    parser = kmbus.Parser()
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
                    got = exchange(s, kmbus.ping(dev_id))
                    self.assertEqual([(f.id, f.status) for f in got], [(dev_id, 0)])
                    got = exchange(s, kmbus.read(dev_id, kmbus.REG_ID))
                    self.assertEqual([(f.id, f.params) for f in got], [(dev_id, bytes([dev_id]))])
                # nobody is left on the default ID
                self.assertEqual(exchange(s, kmbus.ping(0), timeout=0.3), [])
                # super ID: everyone answers, each on the client's wire
                got = exchange(s, kmbus.ping(kmbus.ID_SUPER), timeout=0.5, settle=1)
                self.assertEqual(sorted(f.id for f in got), [1, 2, 3])
            # what servo 1 said on the bus was heard by servos 2 and 3, not echoed to 1
            answer1 = kmbus.encode_status(1, 0)
            self.assertIn(answer1, ln.heard_by(2))
            self.assertIn(answer1, ln.heard_by(3))
            self.assertNotIn(answer1, ln.heard_by(1))
            # the client's bytes reached every servo
            for dev_id in (1, 2, 3):
                self.assertIn(kmbus.ping(2), ln.heard_by(dev_id))
            # provisioning spoke to each servo alone: servo 2 never heard
            # servo 1's write of its ID
            self.assertNotIn(kmbus.write(0, kmbus.REG_ID, b"\x01"), ln.heard_by(2))
            self.assertIn(kmbus.write(0, kmbus.REG_ID, b"\x02"), ln.heard_by(2))
            # the provisioning transcript, alone with each servo: ping 0 until
            # it answers, write 0x0F, then a confirming ping on the new ID
            for dev_id in (1, 2, 3):
                rx = ln.heard_by(dev_id)
                self.assertTrue(rx.startswith(kmbus.ping(0)))
                while rx.startswith(kmbus.ping(0)):
                    rx = rx[len(kmbus.ping(0)):]
                confirm = kmbus.write(0, kmbus.REG_ID, bytes([dev_id])) + kmbus.ping(dev_id)
                self.assertTrue(rx.startswith(confirm), rx.hex())
            # a second client after the first disconnects
            with socket.create_connection(addr) as s:
                got = exchange(s, kmbus.ping(3))
                self.assertEqual([f.id for f in got], [3])
            pids = [ln.pid_of(i) for i in (1, 2, 3)]
        finally:
            rc, out, err = ln.stop()
        self.assertEqual(rc, 0, err)
        self.assertEqual(out, "")  # nothing on stdout after the ready line
        time.sleep(0.1)
        for pid in pids:
            self.assertFalse(pid_alive(pid), "servo pid %d still running" % pid)

    def test_flash_dir_keeps_ids_across_runs(self):
        with tempfile.TemporaryDirectory() as flash_dir:
            for run in (1, 2):
                ln = Launcher([8, 9], extra=("--flash-dir", flash_dir))
                try:
                    _, addr = ln.wait_ready()
                    with socket.create_connection(addr) as s:
                        self.assertEqual([f.id for f in exchange(s, kmbus.ping(9))], [9])
                    heard = ln.heard_by(9)
                finally:
                    rc, _, err = ln.stop()
                self.assertEqual(rc, 0, err)
                wrote = kmbus.write(0, kmbus.REG_ID, b"\x09") in heard
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


if __name__ == "__main__":
    unittest.main()
