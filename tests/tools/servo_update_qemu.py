#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/servo-update on two QEMU servos that boot through the bootloader
(km-servo-boot-qemu-microbit.elf: the bootloader with v1 in its factory
slot; docs/update.md §6), issue 18 item 6:
  - an ID that does not answer is refused before any servo is touched:
    both servos still run v1 (they answer a super-ID ping, which a
    bootloader never does, docs/update.md §3, and 0x0C is unchanged);
  - Ctrl-C (SIGINT, as from a terminal) in the middle of the blocks: one
    short message naming the servos left in their bootloaders and the
    command that finishes the update, status 130, no traceback; the
    servos are in their bootloaders indeed (no super-ID answer); that
    command, run as printed, completes the update: both answer 0x0C =
    v2 and a super-ID ping again;
  - the same through `kmx update` (tools/kmx, host/kmx/update.py), and
    while the servos sit in their bootloaders kmx names them: `kmx get`
    fails with "ID 1 is in update mode ... run `kmx --bus ... update --ids
    1 IMAGE.kmfw`", `kmx ping` says so too, and the command `kmx update`
    printed finishes the job.
Not in tests/tools' discovery (no test_ prefix): it needs the qemu preset's
images, and CTest runs it as update_qemu_interrupt (a missing image fails
it with the command that builds it). About 30 s.
    servo_update_qemu.py [-v]
"""
import os
import re
import select
import shlex
import signal
import struct
import subprocess
import time
import unittest

from kmx.bus import Bus  # noqa: E402  (host/ and sim/bus on PYTHONPATH: tests/CMakeLists.txt)
import simbus  # noqa: E402

REPO = simbus.REPO
BUILD = os.path.join(simbus.build_dir("qemu"), "boards", "qemu-microbit")
BOOT = os.path.join(BUILD, "km-servo-boot-qemu-microbit.elf")
V2 = os.path.join(BUILD, "km-servo-app-v2-qemu-microbit.kmfw")
UPDATE = os.path.join(REPO, "tools", "servo-update")
KMX = os.path.join(REPO, "tools", "kmx")
V1_0X0C, V2_0X0C = 0x10100100, 0x10100102  # bootloader v1.0, hardware 1.0, software 0x0100 / 0x0102


def read_line(proc, seconds):
    """One line of proc's stdout within seconds, or None."""
    ready, _, _ = select.select([proc.stdout], [], [], seconds)
    return proc.stdout.readline() if ready else None


class InterruptedUpdate(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        for f in (BOOT, V2):
            if not os.path.isfile(f):
                raise AssertionError("missing %s: %s" % (f, simbus.build_hint("qemu")))
        cls.bus_proc = subprocess.Popen([os.path.join(REPO, "sim", "bus", "servo-bus"), "--ids", "1,2", "--port", "0",
                                         "--image", BOOT], stdout=subprocess.PIPE, text=True)
        line = read_line(cls.bus_proc, 60) or ""
        if not line.startswith("ready "):
            cls.tearDownClass()
            raise AssertionError("servo-bus did not start: %r" % line)
        cls.spec = "tcp:" + line.split()[1]

    @classmethod
    def tearDownClass(cls):
        cls.bus_proc.send_signal(signal.SIGINT)
        try:
            cls.bus_proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            cls.bus_proc.kill()
            cls.bus_proc.wait()
        cls.bus_proc.stdout.close()

    def servos(self):
        """(IDs answering a super-ID ping, {ID: 0x0C}) of IDs 1 and 2."""
        with Bus(self.spec, timeout=0.3) as bus:
            scanned = sorted(i for i, _ in bus.scan())
            return scanned, {i: struct.unpack("<I", bus.read(i, 0x0C))[0] for i in (1, 2)}

    def test_1_absent_id_touches_nothing(self):
        before = self.servos()
        self.assertEqual(before, ([1, 2], {1: V1_0X0C, 2: V1_0X0C}))
        r = subprocess.run([UPDATE, "--bus", self.spec, "--ids", "1,2,5", V2], capture_output=True, text=True,
                           timeout=120)
        self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
        self.assertEqual(r.stderr, "servo-update: refused, nothing sent to any servo: ID 5 does not answer on "
                                   "%s (kmx --bus %s scan lists the IDs there)\n" % (self.spec, self.spec))
        self.assertEqual(self.servos(), before)  # still the application, never the bootloader

    def interrupt(self, argv, name):
        """Runs argv, sends SIGINT once both servos are erased and the blocks
        go out; returns its stderr lines (status 130 checked)."""
        p = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             env=dict(os.environ, PYTHONUNBUFFERED="1"))
        out = ""
        while "BEGIN:" not in out:  # both erased: the blocks go out now
            line = read_line(p, 60)
            if not line:
                p.kill()
                self.fail("%s printed no BEGIN line:\n%s%s" % (name, out, p.communicate()[1]))
            out += line
        time.sleep(0.5)  # well inside the 238 blocks (4 s at 115200)
        p.send_signal(signal.SIGINT)
        rest, err = p.communicate(timeout=60)
        self.assertNotIn("Traceback", err)
        self.assertEqual(p.returncode, 130, out + rest + err)
        return err.splitlines()

    def finish(self, command):
        """Runs the printed command: both servos end with v2 and answer the super ID."""
        r = subprocess.run(command, capture_output=True, text=True, timeout=180)
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertRegex(r.stdout, re.compile(r"^ID 1: 0x0C = 0x10100102 \(new image\)$", re.M))
        self.assertRegex(r.stdout, re.compile(r"^ID 2: 0x0C = 0x10100102 \(new image\)$", re.M))
        # a super-ID answer can miss its slot on a loaded machine (docs/protocol-decisions.md
        # "Answer slots on emulated buses"): scan again for up to 10 s before failing
        deadline = time.monotonic() + 10
        got = self.servos()
        while got[0] != [1, 2] and time.monotonic() < deadline:
            time.sleep(0.5)
            got = self.servos()
        if got[0] != [1, 2]:
            with Bus(self.spec, timeout=0.3) as bus:
                print("update states after the update: %s" % [bus.update_state(i) for i in (1, 2)], flush=True)
        self.assertEqual(got, ([1, 2], {1: V2_0X0C, 2: V2_0X0C}))

    def test_2_ctrl_c_then_the_printed_command_finishes(self):
        lines = self.interrupt([UPDATE, "--bus", self.spec, "--ids", "1,2", V2], "servo-update")
        self.assertEqual(lines[0], "servo-update: interrupted: ID 1, 2 may be left in their bootloaders (no "
                                   "application runs until the update completes); finish the update with:")
        self.assertEqual(len(lines), 2, lines)
        command = shlex.split(lines[1])
        self.assertEqual(command, [UPDATE, "--bus", self.spec, "--ids", "1,2", V2])
        scanned, versions = self.servos()
        self.assertEqual(scanned, [])  # bootloaders do not answer the super ID
        self.finish(command)

    def test_3_kmx_update_names_update_mode_and_finishes(self):
        lines = self.interrupt([KMX, "--bus", self.spec, "update", "--ids", "1,2", V2], "kmx update")
        self.assertEqual(lines[0], "kmx: interrupted: ID 1, 2 may be left in their bootloaders (no "
                                   "application runs until the update completes); finish the update with:")
        self.assertEqual(len(lines), 2, lines)
        command = shlex.split(lines[1])
        self.assertEqual(command, [KMX, "--bus", self.spec, "update", "--ids", "1,2", V2])
        mode = ("ID 1 is in update mode (its bootloader runs, state receiving; no application): run `kmx --bus %s "
                "update --ids 1 IMAGE.kmfw` to finish the update (docs/update.md)" % self.spec)
        r = subprocess.run([KMX, "--bus", self.spec, "get", "1", "position"], capture_output=True, text=True,
                           timeout=60)
        self.assertEqual((r.returncode, r.stdout, r.stderr), (1, "", "kmx: %s\n" % mode))
        r = subprocess.run([KMX, "--bus", self.spec, "torque", "1", "on"], capture_output=True, text=True,
                           timeout=60)
        self.assertEqual((r.returncode, r.stderr), (1, "kmx: %s\n" % mode))
        r = subprocess.run([KMX, "--bus", self.spec, "ping", "1"], capture_output=True, text=True, timeout=60)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout.splitlines()[1:], [mode])
        self.finish(command)


if __name__ == "__main__":
    unittest.main()
