# SPDX-License-Identifier: Apache-2.0
"""kmx update (and tools/servo-update, its old name): update the firmware of servos on one bus in one broadcast
pass (command 0x78, docs/update.md §4 "A whole-robot update"), or one by
one (--one-by-one: every frame to the servo's own ID, for comparison).

    kmx --bus tcp:127.0.0.1:7000 update --ids 1,2,3 image.kmfw
                 [--rounds N] [--restart-at K ...] [--seed S --restarts N] [--quiet]
                 [--monitor-dir DIR --resets N --seed S]
    kmx --bus ... update --rescue image.kmfw      (one servo alone on the bus, any ID)

image.kmfw: an update image (tools/gen/make-image). Before any frame that
changes a servo: the image is read and checked (magic, length, header and
body CRC-32), and every listed ID must answer a ping and report a
bootloader in 0x0C (bits 31..24, docs/update.md §10; an application run
without one refuses ENTER with bit 5); otherwise one line names the IDs
and nothing is sent. Steps: read each servo's 0x0C; ENTER by broadcast (each restarts into its bootloader); BEGIN by
broadcast, STATUS per ID (a servo that refuses the image, e.g. another
model, is left out and reported); every block by broadcast; STATUS per ID
and the missing blocks again by broadcast (up to --rounds); VERIFY by
broadcast, the wire quiet while the servos compute its CRC passes, STATUS
per ID (VERIFIED); COMMIT likewise (COMMITTED); START by broadcast; 0x0C
per ID again. A broadcast a servo lost (its STATUS shows the state before
the step) is sent to it alone, logged and counted in the figures ("sent
alone after a lost broadcast"; docs/update.md §4).

--rescue: everything by broadcast, no ID needed (the servo must be alone on
the bus); ends by pinging IDs 0..250 to say where it answers.

Testing aids: --restart-at K (repeatable, one per pass) broadcasts the standard
restart (write 0x02 E1 E2 E3 E4, a system reset of every servo) right
after the K-th frame of that pass; --restarts N with --seed S draws N such
points at random over the whole pass (ENTER to START), one per pass. After a restart the servos lose the session (their RAM): the tool
notices on the next STATUS and starts the pass again from ENTER, so every
run ends updated or reports why.

--resets N with --monitor-dir DIR (the servos' QEMU monitors, sim/bus/servo-bus
--monitor-dir DIR) and --seed S: N real system resets ("system_reset" on
one servo's QEMU monitor, the emulated equivalent of a power cut: the core,
RAM and peripherals restart, flash keeps what was written) at random
points over the pass: a random frame (or, for half of them, the pass's
next ENTER, BEGIN and its erase, VERIFY, COMMIT and its commit cell, or
START), a random servo, fired by a timer a
random time after the frame starts to go out (0 to 1.5 times its line
time), so it lands while the frame is on the wire, while the servo decodes
it, or while it erases or programs for it. QEMU's NVMC completes an erase or
a program inside one guest instruction, so a reset lands between two flash
operations, never inside one (no torn cell: that is the host runner's job,
tests/unit/update/test_update_powercut.c). After each reset every servo must answer
a ping (bootloader or application) and its STATUS state is recorded; the
pass then notices a lost session and starts again. Figures (bytes of image, frames, seconds,
bytes of image per second) are printed at the end.

A stop once an ENTER went out (Ctrl-C, a lost bus, a pass that gives up)
leaves servos in their bootloaders, with no application running: the tool
then names them and prints the command that finishes the update (the same
bus, IDs and image, without the testing aids; --rescue stays --rescue).

Exit status: 0 all servos updated, 1 some not (or refused by the checks
above: an ID absent, no bootloader), 2 a bad command line, image or bus
spec (one line), 130 Ctrl-C; never a traceback.
"""
import argparse
import os
import random
import shlex
import signal
import socket
import struct
import sys
import threading
import time
import zlib

from . import frame as fr
from .bus import Bus
from .errors import KmxError

CMD = 0x78
ENTER, BEGIN, WRITE, STATUS, VERIFY, COMMIT, START = 1, 2, 3, 4, 5, 6, 7
ENTER_MAGIC = bytes([0xB1, 0xB2, 0xB3, 0xB4])
START_MAGIC = bytes([0xE1, 0xE2, 0xE3, 0xE4])
BLOCK = 128
BCAST = 0xFE
STATES = {0: "application", 1: "idle", 2: "receiving", 3: "verified", 4: "committed", 5: "failed"}
RESULTS = {0: "ok", 1: "bad length", 2: "bad state", 3: "bad magic", 4: "bad header",
           5: "wrong model", 6: "too big", 7: "bad block", 8: "bad block CRC", 9: "mismatch",
           10: "flash error", 11: "verify failed", 12: "blocks missing"}
BOOT_WAIT_S = 5.0
# After a broadcast block the servos program it, and a bootloader fetching
# from flash meanwhile does not read the bus (docs/update.md §4): G0, 16
# double words x 85 us = 1.36 ms; the master keeps the wire quiet this long.
PROGRAM_GAP_S = 0.002
# VERIFY reads the image back twice (its CRC-32 over the whole image, then
# the body's), COMMIT's boot check once more, and a bootloader computing
# does not read the bus (docs/update.md §4 "After VERIFY and COMMIT"): one
# pass costs 23 instructions, about 33 M0+ cycles, a byte (the G031
# bootloader's read loop and nibble CRC); the master budgets 50 and leaves
# the wire quiet that long at the bootloader's clock, by the image's model.
CRC_PASS_CYCLES_PER_BYTE = 50
BOOT_CLOCK_HZ = {0x4B4D0001: 16000000, 0x4B4D0002: 16000000}  # qemu-microbit, stm32g031: reset clocks
BUSY_FLOOR_S = 0.01
VERIFY_PASSES, COMMIT_PASSES = 2, 1
ALONE = ("ENTER", "BEGIN", "VERIFY", "COMMIT", "START")  # the frames a lost broadcast sends again


class Monitor:
    """One servo's QEMU human monitor (a Unix socket, sim/bus/servo-bus
    --monitor-dir), kept open for the whole run so a reset costs no connect."""

    def __init__(self, path):
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.sock.connect(path)
        self.sock.settimeout(5.0)
        self._prompt()

    def _prompt(self):
        """Reads up to the next prompt: the monitor's text before it."""
        got = b""
        while not got.endswith(b"(qemu) "):
            chunk = self.sock.recv(4096)
            if not chunk:
                raise OSError("monitor closed")
            got += chunk
        return got.decode(errors="replace")

    def system_reset(self):
        self.sock.sendall(b"system_reset\n")
        self._prompt()


class Restarted(Exception):
    """The servos lost their session (an injected or a real reset)."""


def frame(dev_id, sub, params=b""):
    return fr.encode_command(dev_id, CMD, sub, params)


class Updater:
    def __init__(self, bus, ids, image, log, restart_after=()):
        self.bus, self.ids, self.image, self.log = bus, list(ids), image, log
        self.blocks = (struct.unpack_from("<I", image, 8)[0] + BLOCK - 1) // BLOCK
        self.padded = image + b"\xff" * (self.blocks * BLOCK - len(image))
        self.dest = BCAST          # where the pass's frames go (--one-by-one: the ID)
        self.baud = 115200
        self.wire_free = 0.0
        self.plan = list(restart_after)  # per pass: restart after this many of its frames
        self.at = None
        self.pass_frames = 0
        self.frames = 0
        self.restarts_done = 0
        self.unreachable = 0    # servos that did not answer a ping after an injected restart
        self.monitors = {}      # ID -> Monitor (--resets)
        self.resets_done = 0
        self.reset_log = []     # (ID reset, frame description, delay ms, line ms, {ID: state after})
        self.bytes_sent = 0
        self.left_out = {}
        self.touched = False    # an ENTER went out: servos may sit in their bootloaders
        self.pending = list(ids)  # not through a whole pass yet
        self.alone = dict.fromkeys(ALONE, 0)  # frames sent again to one servo after a lost broadcast

    def busy_s(self, passes):
        """How long a bootloader reads no bus while it runs `passes` CRC-32
        passes over this image (VERIFY 2, COMMIT's boot check 1), at its
        board's clock with the margin of CRC_PASS_CYCLES_PER_BYTE."""
        model, length = struct.unpack_from("<II", self.image, 4)
        hz = BOOT_CLOCK_HZ.get(model, min(BOOT_CLOCK_HZ.values()))
        return passes * length * CRC_PASS_CYCLES_PER_BYTE / hz + BUSY_FLOOR_S

    def sent_alone(self, dev_id, what):
        """Counts and logs a frame sent again to one servo after its broadcast was lost."""
        self.alone[what] += 1
        self.log("  ID %d missed %s: sent to it alone" % (dev_id, what))

    # -- wire --------------------------------------------------------------
    def start_pass(self):
        self.pass_frames = 0
        self.at = self.plan.pop(0) if self.plan else None

    def pace(self, nbytes):
        """Holds the master to the line rate: on a wire it cannot send
        faster, and an emulated bus (which hands bytes over as fast as the
        emulators read them) must not queue seconds of frames behind a
        question."""
        now = time.monotonic()
        if self.wire_free > now:
            time.sleep(self.wire_free - now)
        self.wire_free = max(now, self.wire_free) + nbytes * 10.0 / self.baud

    def quiet_for(self, seconds):
        """No frame for `seconds` after the one just sent (the servos' program time)."""
        self.wire_free = max(time.monotonic(), self.wire_free) + seconds

    def send(self, data, answers=0, timeout=None):
        self.pace(len(data))
        self.frames += 1
        self.pass_frames += 1
        self.bytes_sent += len(data)
        if isinstance(self.at, tuple) and (
                self.pass_frames >= self.at[0] if not self.at[3] else
                len(data) > 5 and data[4] == CMD and data[5] == self.at[3]):
            return self.send_with_reset(data, answers, timeout)
        out = self.bus.transact(data, answers, timeout)
        if self.at is not None and not isinstance(self.at, tuple) and self.pass_frames >= self.at:
            self.at = None
            self.restarts_done += 1
            self.log("  (injected: restart broadcast after frame %d of the pass)" % self.pass_frames)
            self.bus.transact(fr.restart(BCAST))
            time.sleep(0.3)
            # Reachable again: each servo (bootloader or application) pings back.
            for i in self.ids:
                if i != BCAST and not self.wait_boot(i):
                    self.unreachable += 1
                    self.log("  ID %d does NOT answer after the restart" % i)
        return out

    def send_with_reset(self, data, answers, timeout):
        """Sends data while a timer resets one servo through its QEMU
        monitor at a random moment of the frame (planned in self.at), then
        checks that every servo answers and records its state."""
        _, dev_id, frac, _ = self.at
        self.at = None
        line_s = len(data) * 10.0 / 115200
        delay = frac * 1.5 * line_s
        what = "0x78 %02X" % data[5] if len(data) > 5 and data[4] == CMD else "cmd %02X" % data[4]
        if len(data) > 7 and data[4] == CMD and data[5] == WRITE:
            what += " block %d" % struct.unpack_from("<H", data, 6)[0]
        timer = threading.Timer(delay, self.monitors[dev_id].system_reset)
        timer.start()
        out = self.bus.transact(data, answers, timeout)
        timer.join()
        self.resets_done += 1
        time.sleep(0.2)
        after = {}
        for i in self.ids:
            if not self.wait_boot(i):
                self.unreachable += 1
                after[i] = "NO ANSWER"
                continue
            st = self.status(i)
            after[i] = "no STATUS" if st is None else STATES.get(st["state"], st["state"])
        self.reset_log.append((dev_id, what, delay * 1000, line_s * 1000, after))
        self.log("  (injected: system_reset of ID %d %.1f ms into frame %d of the pass, %s, "
                 "line time %.1f ms; after: %s)" % (
                     dev_id, delay * 1000, self.pass_frames, what, line_s * 1000,
                     ", ".join("ID %d %s" % kv for kv in sorted(after.items()))))
        return out

    def ask(self, dev_id, sub, params=b"", timeout=2.0, tries=6):
        """The answer's parameters to a 0x78 frame sent to dev_id, or None
        (after 12 s: an emulated servo on a loaded machine works through a
        backlog of blocks for seconds before it reads the question).
        Short responses are skipped: a late answer to an earlier ping (a
        servo that was restarting answers the pings it queued) must not
        pass for this answer."""
        for _ in range(tries):
            self.send(frame(dev_id, sub, params))
            end = time.monotonic() + timeout
            while time.monotonic() < end:
                for f in self.bus.listen(end - time.monotonic(), 1):
                    if f.id == dev_id and not f.is_status and f.cmd == CMD and f.addr == sub:
                        return f.params
        return None

    def status(self, dev_id, first=0):
        p = self.ask(dev_id, STATUS, struct.pack("<H", first))
        if p is None or len(p) < 8:
            return None
        state, result, blocks, received, first_ = struct.unpack_from("<BBHHH", p)
        return {"state": state, "result": result, "blocks": blocks, "received": received,
                "bitmap": p[8:]}

    def wait_boot(self, dev_id, seconds=BOOT_WAIT_S):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            for f in self.bus.transact(fr.ping(dev_id), 1, 0.2):
                if f.id == dev_id and f.is_status:
                    return True
        return False

    def version(self, dev_id):
        for _ in range(5):
            for f in self.bus.transact(fr.read(dev_id, 0x0C), 1, 0.3):
                if f.id == dev_id and not f.is_status and f.addr == 0x0C and len(f.params) == 4:
                    return struct.unpack("<I", f.params)[0]
        return None

    # -- the pass ----------------------------------------------------------
    def missing(self, dev_id):
        out = []
        for first in range(0, self.blocks, 512):
            st = self.status(dev_id, first)
            if st is None:
                raise Restarted("ID %d does not answer STATUS" % dev_id)
            if st["state"] not in (2, 3):
                raise Restarted("ID %d is %s" % (dev_id, STATES.get(st["state"], st["state"])))
            for i in range(min(512, self.blocks - first)):
                if not st["bitmap"][i // 8] >> (i % 8) & 1:
                    out.append(first + i)
        return out

    def one_pass(self, rounds):
        self.start_pass()
        ids = [i for i in self.ids if i not in self.left_out]
        self.touched = True
        self.send(frame(self.dest, ENTER, ENTER_MAGIC))
        time.sleep(0.2)
        for i in ids:
            if not self.wait_boot(i):
                raise Restarted("ID %d does not answer after ENTER" % i)
        self.send(frame(self.dest, BEGIN, self.image[:32]))
        time.sleep(0.2)
        for i in ids:
            st = self.status(i)
            if st is None:
                raise Restarted("ID %d: no STATUS after BEGIN" % i)
            if st["state"] == 0:
                # Still the application: the broadcast ENTER was lost.
                self.sent_alone(i, "ENTER")
                self.send(frame(i, ENTER, ENTER_MAGIC))
                time.sleep(0.2)
                self.wait_boot(i)
                st = {"state": 1, "result": 0}
            if st["state"] == 1 and st["result"] == 0:
                # The broadcast BEGIN did not reach it (a frame lost): its own.
                self.sent_alone(i, "BEGIN")
                self.ask(i, BEGIN, self.image[:32], timeout=2.0)
                st = self.status(i)
                if st is None:
                    raise Restarted("ID %d: no STATUS after BEGIN" % i)
            if st["result"] in (4, 5, 6):
                self.left_out[i] = RESULTS[st["result"]]
                self.log("  ID %d refuses the image: %s (nothing erased)" % (i, RESULTS[st["result"]]))
            elif st["state"] != 2:
                raise Restarted("ID %d: %s after BEGIN (%s)" % (
                    i, STATES.get(st["state"]), RESULTS.get(st["result"])))
        ids = [i for i in ids if i not in self.left_out]
        if not ids:
            self.send(frame(self.dest, START, START_MAGIC))  # back to what they ran
            time.sleep(0.2)
            return []
        self.log("  BEGIN: ID %s erased; sending %d blocks" % (", ".join(map(str, ids)), self.blocks))
        todo = list(range(self.blocks))
        for r in range(rounds):
            for b in todo:
                data = self.padded[b * BLOCK:(b + 1) * BLOCK]
                wr = frame(self.dest, WRITE, struct.pack("<H", b) + data +
                           struct.pack("<I", zlib.crc32(data) & 0xFFFFFFFF))
                if self.dest == BCAST:
                    self.send(wr)
                    self.quiet_for(PROGRAM_GAP_S)
                else:
                    self.send(wr, 1, 0.5)  # to one ID: wait for its answer, as on a wire
            need = set()
            for i in ids:
                need.update(self.missing(i))
            if not need:
                break
            self.log("  round %d: %d blocks missing somewhere, sent again" % (r + 1, len(need)))
            todo = sorted(need)
        else:
            raise Restarted("blocks still missing after %d rounds" % rounds)
        self.step(VERIFY, VERIFY_PASSES)
        self.confirm(ids, VERIFY, 3)
        self.step(COMMIT, COMMIT_PASSES)
        self.confirm(ids, COMMIT, 4)
        self.send(frame(self.dest, START, START_MAGIC))
        time.sleep(0.2)
        self.restart_missed(ids)
        return ids

    def step(self, sub, passes):
        """VERIFY or COMMIT to the pass's destination, and the wait for its
        CRC passes: by broadcast (no answer) the wire stays quiet for
        busy_s(passes); to one ID its answer, which comes once it is done."""
        if self.dest == BCAST:
            self.send(frame(BCAST, sub))
            self.quiet_for(self.busy_s(passes))
        else:
            t0 = time.monotonic()
            got = self.ask(self.dest, sub, timeout=max(2.0, 2 * self.busy_s(passes)))
            if got is not None:
                self.log("  ID %d: %s answered %.1f ms after it was sent (budget %.1f ms)" % (
                    self.dest, "VERIFY" if sub == VERIFY else "COMMIT", (time.monotonic() - t0) * 1000,
                    self.busy_s(passes) * 1000))

    def confirm(self, ids, sub, state):
        """STATUS of each ID after VERIFY or COMMIT (docs/update.md §4): the
        state it leads to (3 VERIFIED, 4 COMMITTED); the state before it
        means the frame was lost: sent again to that servo alone, whose
        answer comes once it is done. Restarted for anything else."""
        for i in ids:
            st = self.status(i)
            if st is not None and st["state"] == state - 1:
                self.sent_alone(i, "VERIFY" if sub == VERIFY else "COMMIT")
                self.ask(i, sub, timeout=max(2.0, 2 * self.busy_s(VERIFY_PASSES)))
                st = self.status(i)
            if st is None or st["state"] != state:
                raise Restarted("ID %d not %s: %s" % (
                    i, STATES[state], st and (STATES.get(st["state"]), RESULTS.get(st["result"]))))

    def restart_missed(self, ids):
        """A lost broadcast START leaves a servo committed in its bootloader:
        STATUS finds it (an application answers state 0), START to it alone."""
        for i in ids:
            st = self.status(i)
            if st is not None and st["state"] == 4:
                self.sent_alone(i, "START")
                self.send(frame(i, START, START_MAGIC))
                time.sleep(0.2)

    def rescue_pass(self, rounds):
        """Everything by broadcast, blind: the servo is alone on the bus and
        its ID unknown. Re-sent blocks are no-ops on a servo that has them."""
        self.touched = True
        self.send(frame(BCAST, ENTER, ENTER_MAGIC))
        time.sleep(1.0)
        self.send(frame(BCAST, BEGIN, self.image[:32]))
        time.sleep(2.0)  # the longest erase: G0, 25 pages x 40 ms
        for _ in range(max(1, rounds)):
            for b in range(self.blocks):
                data = self.padded[b * BLOCK:(b + 1) * BLOCK]
                self.send(frame(BCAST, WRITE, struct.pack("<H", b) + data +
                                struct.pack("<I", zlib.crc32(data) & 0xFFFFFFFF)))
                self.quiet_for(PROGRAM_GAP_S)
        self.send(frame(BCAST, VERIFY))
        self.quiet_for(self.busy_s(VERIFY_PASSES))
        self.send(frame(BCAST, COMMIT))
        self.quiet_for(self.busy_s(COMMIT_PASSES))
        time.sleep(0.1)
        self.send(frame(BCAST, START, START_MAGIC))
        time.sleep(1.0)
        return []


class Refused(Exception):
    """A bad input or a check before the update: one line, nothing sent to
    any servo; args[1] is the exit status."""


class OneLineParser(argparse.ArgumentParser):
    """argparse whose command-line errors are one line and status 2."""

    def error(self, message):
        raise Refused("%s (%s --help)" % (message, self.prog), 2)


def count_arg(least):
    """An argparse type: a whole number of at least `least`."""
    def parse(text):
        try:
            v = int(text, 10)
        except ValueError:
            v = least - 1
        if v < least:
            raise argparse.ArgumentTypeError("'%s' is not a whole number of at least %d" % (text, least))
        return v
    return parse


def ids_arg(text):
    """--ids: distinct servo IDs 0..250, comma-separated."""
    ids = []
    for part in text.split(","):
        try:
            v = int(part.strip(), 10)
        except ValueError:
            raise argparse.ArgumentTypeError("'%s' is not a servo ID (0..%d)" % (part, fr.ID_MAX)) from None
        if not 0 <= v <= fr.ID_MAX:
            raise argparse.ArgumentTypeError("servo ID %d is outside 0..%d" % (v, fr.ID_MAX))
        if v in ids:
            raise argparse.ArgumentTypeError("ID %d is listed twice" % v)
        ids.append(v)
    return ids


def add_update_arguments(ap, with_bus):
    """The update's options on ap (servo-update's parser, or kmx's `update`
    subcommand, whose --bus is kmx's own)."""
    if with_bus:
        ap.add_argument("--bus", required=True, help="tcp:HOST:PORT, serial:/dev/ttyUSB0@115200, ...")
    ap.add_argument("--ids", type=ids_arg, help="comma-separated IDs")
    ap.add_argument("--rescue", action="store_true", help="one servo alone on the bus, any ID: all by broadcast")
    ap.add_argument("--rounds", type=count_arg(1), default=4, help="passes over missing blocks (default 4)")
    ap.add_argument("--restart-at", type=count_arg(1), action="append", default=[],
                    help="testing: broadcast a restart after the K-th frame of a pass")
    ap.add_argument("--restarts", type=count_arg(0), default=0, help="testing: N restarts at random points")
    ap.add_argument("--seed", type=int, default=1, help="testing: the random points' seed")
    ap.add_argument("--resets", type=count_arg(0), default=0,
                    help="system resets through the servos' QEMU monitors (needs --monitor-dir)")
    ap.add_argument("--monitor-dir", help="the servos' QEMU monitor sockets (sim/bus/servo-bus --monitor-dir)")
    ap.add_argument("--attempts", type=count_arg(0), default=0, help="passes at most (default: restarts + 3)")
    ap.add_argument("--quiet", action="store_true", help="only the figures and the errors")
    ap.add_argument("--baud", type=count_arg(0), default=115200,
                    help="line rate the frames are paced at (default 115200; 0: no pacing)")
    ap.add_argument("--one-by-one", action="store_true",
                    help="update the servos one after the other, every frame to its ID "
                         "(the comparison for the broadcast pass)")
    ap.add_argument("image", help="the update image (tools/gen/make-image)")


def check_args(a):
    """The checks argparse cannot make: Refused (status 2)."""
    if a.rescue == (a.ids is not None):
        raise Refused("give --ids (the servos to update) or --rescue (one servo alone "
                      "on the bus)%s" % (", not both" if a.rescue else ""), 2)
    if a.resets and (not a.monitor_dir or a.rescue):
        raise Refused("--resets needs --monitor-dir and --ids", 2)
    return a


def parse_args(argv, prog="servo-update"):
    """servo-update's command line, checked: Refused (status 2) for anything wrong."""
    ap = OneLineParser(prog=prog, description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_update_arguments(ap, True)
    a = check_args(ap.parse_args(argv))
    a.prog = prog
    a.finish_argv = [sys.argv[0], "--bus", a.bus]
    a.trace = None
    return a


def load_image(path):
    """The update image's bytes, checked as BEGIN and VERIFY will check
    them (docs/update.md §2), or Refused."""
    try:
        with open(path, "rb") as f:
            image = f.read()
    except OSError as e:
        raise Refused("cannot read the image %s: %s" % (path, e.strerror or e), 2) from None
    if len(image) < 0x108 or image[:4] != b"KMFW":
        raise Refused("%s is not an update image (tools/gen/make-image)" % path, 2)
    if zlib.crc32(image[:28]) & 0xFFFFFFFF != struct.unpack_from("<I", image, 28)[0]:
        raise Refused("%s: header CRC does not match" % path, 2)
    length = struct.unpack_from("<I", image, 8)[0]
    if length != len(image):
        raise Refused("%s: the header says %d bytes, the file has %d" % (path, length, len(image)), 2)
    if zlib.crc32(image[32:]) & 0xFFFFFFFF != struct.unpack_from("<I", image, 24)[0]:
        raise Refused("%s: body CRC does not match (a damaged image)" % path, 2)
    return image


def plan_restarts(a, image, ids):
    """The injection points (--restart-at, --restarts, --resets) and the passes allowed."""
    points = list(a.restart_at)
    blocks = (len(image) + BLOCK - 1) // BLOCK
    attempts = a.attempts
    if a.restarts:
        rng = random.Random(a.seed)
        frames_per_pass = blocks + 2 + 2 * len(ids)  # frames every pass sends, at least
        points += [rng.randrange(1, frames_per_pass) for _ in range(a.restarts)]
        attempts = attempts or 2 * a.restarts + 3
    if a.resets:
        rng = random.Random(a.seed * 7919 + 1)
        n = len(ids)
        # Frames of a pass with nothing lost, in order: ENTER, BEGIN, n STATUS,
        # the blocks, n x (STATUS per 512 blocks), VERIFY, n STATUS, COMMIT,
        # n STATUS, START.
        total = blocks + 5 + n * (3 + (blocks + 511) // 512)
        for _ in range(a.resets):
            # Half at a random frame of the pass (mostly WRITE: programs),
            # half at the next ENTER, BEGIN (the erase), VERIFY, COMMIT (the
            # commit cell) or START, which a draw over frames would hit
            # once in 250.
            if rng.random() < 0.5:
                points.append((rng.randrange(1, total + 1), rng.choice(ids), rng.random(), 0))
            else:
                points.append((0, rng.choice(ids), rng.random(),
                               rng.choice((ENTER, BEGIN, VERIFY, COMMIT, START))))
        attempts = attempts or 2 * (a.restarts + a.resets) + 3
    return points, attempts or (len(points) + 3)


def preflight(up, ids, spec):
    """Before any frame that changes a servo: every listed ID answers a ping
    and reports a bootloader in 0x0C (bits 31..24, docs/update.md §10: 0 =
    an application started without one, which refuses ENTER with bit 5).
    Returns {ID: 0x0C}; Refused naming the IDs otherwise."""
    absent, versions = [], {}
    for i in ids:
        if not up.wait_boot(i, 2.0):
            absent.append(i)
            continue
        versions[i] = up.version(i)
    silent = [i for i, v in versions.items() if v is None]
    bare = [i for i, v in versions.items() if v is not None and v >> 24 == 0]
    why = []
    if absent:
        why.append("ID %s do%s not answer on %s (kmx --bus %s scan lists the IDs there)"
                   % (", ".join(map(str, absent)), "es" if len(absent) == 1 else "", spec, spec))
    if silent:
        why.append("ID %s answer%s a ping but not a read of 0x0C"
                   % (", ".join(map(str, silent)), "s" if len(silent) == 1 else ""))
    if bare:
        why.append("ID %s ha%s no bootloader (0x0C %s, bootloader byte 0; docs/update.md §10): flash one "
                   "with a programmer first" % (", ".join(map(str, bare)), "s" if len(bare) == 1 else "ve",
                                                ", ".join("0x%08X" % versions[i] for i in bare)))
    if why:
        raise Refused("refused, nothing sent to any servo: %s" % "; ".join(why), 1)
    return versions


def finish_command(a, ids):
    """The command line that takes the servos in ids through a whole update
    again (the testing aids left out): the same bus, image, pacing and rounds."""
    argv = list(a.finish_argv)
    argv += ["--rescue"] if a.rescue else ["--ids", ",".join(map(str, ids))]
    if a.baud != 115200:
        argv += ["--baud", str(a.baud)]
    if a.rounds != 4:
        argv += ["--rounds", str(a.rounds)]
    return " ".join(shlex.quote(x) for x in argv + [a.image])


def stopped(a, up, ids, why, status):
    """After a stop: one line why, and if servos may sit in their bootloaders
    (an ENTER went out), which, and the command that finishes the update."""
    if not up.touched:
        print("%s: %s; no servo was touched" % (a.prog, why), file=sys.stderr, flush=True)
        return status
    who = "the servo on the bus" if a.rescue else "ID %s" % ", ".join(map(str, ids))
    print("%s: %s: %s may be left in %s bootloader%s (no application runs until the update "
          "completes); finish the update with:\n  %s"
          % (a.prog, why, who, "its" if a.rescue or len(ids) == 1 else "their", "" if a.rescue or len(ids) == 1 else "s",
             finish_command(a, ids)), file=sys.stderr, flush=True)
    return status


def run_groups(up, a, ids, points, attempts, log):
    """Every group through its pass (all IDs at once, or one by one
    --one-by-one); the IDs updated, or None when a group gave up."""
    groups = [[i] for i in ids] if a.one_by_one else [ids]
    done = []
    again = 0
    gi = 0
    while gi < len(groups):
        group = groups[gi]
        up.ids = group
        up.dest = group[0] if a.one_by_one else BCAST
        got = None
        for n in range(attempts):
            try:
                got = up.rescue_pass(2) if a.rescue else up.one_pass(a.rounds)
                break
            except Restarted as e:
                log("  pass %d interrupted: %s; starting again" % (n + 1, e))
                if up.at is not None:
                    up.plan.insert(0, up.at)  # not injected yet: it stays for the next pass
                    up.at = None
                time.sleep(0.3)
        if got is None:
            return None
        done = [i for i in done if i not in got] + got
        up.pending = [i for i in up.pending if i not in group]
        if up.at is not None:  # the pass ended before its restart point
            up.plan.insert(0, up.at)
            up.at = None
        gi += 1
        # A pass can complete around an injected restart (one right after
        # ENTER is absorbed by the retries): while restarts remain planned,
        # the last update runs again, so every planned one lands in a pass.
        if gi == len(groups) and up.plan and again < len(points) + 2:
            again += 1
            log("  %d injections still planned: the update runs again" % len(up.plan))
            gi -= 1
    return done


def check_result(up, a, done, new_version, log):
    """Reads 0x0C of every updated servo (or finds the rescued one); True if all have the image."""
    ok = True
    if a.rescue:
        for i in range(251):
            if up.wait_boot(i, 0.05):
                log("rescued servo answers on ID %d" % i)
                break
        return ok
    for i in done:
        up.wait_boot(i)
        v = up.version(i)
        good = v is not None and (v & 0xFFFFFF) == (new_version & 0xFFFFFF)
        ok &= good
        log("ID %d: 0x0C = %s %s" % (i, "0x%08X" % v if v is not None else "no answer",
                                    "(new image)" if good else "(NOT updated)"))
    for i, why in up.left_out.items():
        log("ID %d: left out: %s" % (i, why))
        ok = False
    return ok


def print_figures(up, a, image, done, seconds):
    """The run's figures: resets and the states they left, bytes, frames, seconds."""
    if a.resets:
        tally = {}
        for _, _, delay, line, after in up.reset_log:
            for i, st in after.items():
                tally.setdefault(i, {}).setdefault(st, 0)
                tally[i][st] += 1
        inside = sum(1 for r in up.reset_log if r[2] < r[3])
        print("%s: %d system resets injected (%d while the frame was on the wire, %d after "
              "it: decode, erase, program); states right after a reset: %s" % (
                  a.prog, up.resets_done, inside, up.resets_done - inside,
                  "; ".join("ID %d %s" % (i, ", ".join("%s %d" % kv for kv in sorted(t.items())))
                            for i, t in sorted(tally.items()))), flush=True)
    print("%s: %s, %d bytes of image, %d frames (%d bytes) in %.2f s: "
          "%.0f bytes of image per second; %d restarts injected, %d resets injected, %d times a "
          "servo did not answer after one; sent alone after a lost broadcast: %s"
          % (a.prog, "rescue (1 servo, blind)" if a.rescue else "%d servo(s)" % len(done), len(image), up.frames,
             up.bytes_sent, seconds, len(image) / seconds, up.restarts_done, up.resets_done, up.unreachable,
             ", ".join("%s %d" % (k, up.alone[k]) for k in ALONE)),
          flush=True)


def open_updater(a, image, ids, points, log):
    """The bus and the Updater on it (with the QEMU monitors of --resets), or Refused."""
    try:
        bus = Bus(a.bus, timeout=0.3, retries=2, trace=a.trace)
    except KmxError as e:
        raise Refused(str(e), 2) from None
    up = Updater(bus, ids, image, log, points)
    for i in ids if a.resets else []:
        try:
            up.monitors[i] = Monitor(os.path.join(a.monitor_dir, "servo-%d.sock" % i))
        except OSError as e:
            raise Refused("monitor of ID %d: %s" % (i, e), 2) from None
    up.baud = a.baud if a.baud > 0 else 10 ** 12
    return up


def update(a, up, image, ids, points, attempts, log):
    """The update itself, after the checks: exit status 0 all updated, 1 not."""
    new_version = struct.unpack_from("<I", image, 12)[0]
    t0 = time.monotonic()
    done = run_groups(up, a, ids, points, attempts, log)
    seconds = time.monotonic() - t0
    up.ids = ids
    if done is None:
        return stopped(a, up, up.pending, "gave up after %d passes" % attempts, 1)
    ok = check_result(up, a, done, new_version, log)
    print_figures(up, a, image, done, seconds)
    return 0 if ok and up.unreachable == 0 else 1


def run(a):
    """The update of the checked command line a (a.prog names the command in
    messages, a.finish_argv starts the command printed after a stop): exit
    status 0 all updated, 1 not (or refused by the checks), 2 a bad input,
    130 Ctrl-C; never a traceback."""
    up = None
    try:
        log = (lambda m: None) if a.quiet else (lambda m: print(m, flush=True))
        image = load_image(a.image)
        ids = [BCAST] if a.rescue else a.ids
        points, attempts = plan_restarts(a, image, ids)
        up = open_updater(a, image, ids, points, log)
        log("image: %d bytes, %d blocks, version 0x%08X" % (
            len(image), up.blocks, struct.unpack_from("<I", image, 12)[0]))
        if not a.rescue:
            for i, v in preflight(up, ids, a.bus).items():
                log("ID %d: 0x0C = 0x%08X" % (i, v))
        return update(a, up, image, ids, points, attempts, log)
    except Refused as e:
        print("%s: %s" % (a.prog, e.args[0]), file=sys.stderr, flush=True)
        return e.args[1]
    except KeyboardInterrupt:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # one Ctrl-C is enough: say how to go on
        if up is None:
            print("%s: interrupted; no servo was touched" % a.prog, file=sys.stderr, flush=True)
            return 130
        return stopped(a, up, up.pending, "interrupted", 130)
    except (KmxError, OSError) as e:
        if up is None:
            print("%s: %s" % (a.prog, e), file=sys.stderr, flush=True)
            return 1
        return stopped(a, up, up.pending, str(e), 1)
    finally:
        if up is not None:
            up.bus.close()


def main(argv=None, prog="servo-update"):
    """servo-update's entry: the command line, then run()."""
    signal.signal(signal.SIGINT, signal.default_int_handler)  # Ctrl-C from here: KeyboardInterrupt
    try:
        a = parse_args(argv, prog)
    except Refused as e:
        print("%s: %s" % (prog, e.args[0]), file=sys.stderr, flush=True)
        return e.args[1]
    except KeyboardInterrupt:
        print("%s: interrupted; no servo was touched" % prog, file=sys.stderr, flush=True)
        return 130
    return run(a)
