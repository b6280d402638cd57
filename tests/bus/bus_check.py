#!/usr/bin/env python3
"""Whole servos on a bus, spoken to over bytes only (tests/bus.cmake runs it).

  bus_check.py smoke --backend qemu      one servo: PROTOCOL.md §3 basics
  bus_check.py bus   --backend qemu      three servos: super ID, broadcast,
                                         other servos' responses on the wire
  bus_check.py encoder --backend host-sim  the encoder product (--product
                                         encoder to servo-bus): model name,
                                         0x6F turns it past 360 deg, 0 stops
                                         it, a restart reads the angle within
                                         one turn; the pot product refuses 0x6F
  [--gap-floor-us N]  passed to tools/servo-bus (tests/bus.cmake: 0 for host-sim)
  [--build-dir DIR]   the backend's build tree (default: servo-bus's, which
                      also reads KM_BUILD_QEMU / KM_BUILD_HOST_SIM)

Starts tools/servo-bus (which runs the built images), waits for its `ready`
line, then acts as the bus master. Exits non-zero on the first mismatch.

Both backends, smoke and bus: the servo moves (torque on, 0x65 to +45.0 deg
in 500 ms, 0x46 read until it arrives, 0x66 back, 0x70 motor mode for 0.5 s
that stops by itself, torque off); on the bus, a 0x83 multi-ID 0x65 sends
all three to their own targets at once and each arrives.

host-sim only (its UART runs at the servo's baud and stamps each byte with
its wire time, so both are faithful there): a burst far over the servo's
128-byte RX queue in one TCP write, every frame answered; and a frame whose
bytes stop for longer than the gap, dropped, the next frame answered. QEMU's
UART moves bytes at host speed, so a burst overtakes the answers and a
pause inside a frame is not guaranteed to reach the guest as a pause.

Why the QEMU bus runs at 9600 baud: QEMU's UART sends instantly whenever the
host schedules that QEMU process, so three emulators on two cores jitter by
about a millisecond; a super-ID slot at 115200 baud is 0.7 ms (see
docs/protocol-decisions.md), at 9600 baud 8.3 ms. The servos are switched
over the protocol itself (broadcast write 0x10, broadcast restart).
"""
import argparse
import os
import socket
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import kmbus  # noqa: E402


GAP_FLOOR_DEFAULT_US = 20000  # the emulated boards' own default


class Bus:
    def __init__(self, backend, ids, opts):
        argv = [sys.executable, os.path.join(ROOT, "tools", "servo-bus"), "--ids",
                ",".join(map(str, ids)), "--port", "0", "--backend", backend, "--timeout", "30"]
        if opts.gap_floor_us is not None:
            argv += ["--gap-floor-us", str(opts.gap_floor_us)]
        if opts.build_dir:
            argv += ["--build-dir", opts.build_dir]
        if getattr(opts, "product", None):
            argv += ["--product", opts.product]
        self.proc = subprocess.Popen(argv, stdout=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline().strip()
        if not line.startswith("ready "):
            self.proc.wait(5)
            raise SystemExit("servo-bus did not get ready (exit %s)" % self.proc.returncode)
        host, port = line.split()[1].rsplit(":", 1)
        self.sock = socket.create_connection((host, int(port)))
        # A frame written in pieces must leave at once: with Nagle a piece can
        # wait ~40 ms for the ACK of the last one, longer than the gap rule.
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.parser = kmbus.Parser()

    def close(self):
        self.sock.close()
        self.proc.terminate()
        self.proc.wait(10)

    def exchange(self, frame, expect, timeout=2.0, quiet=False):
        """Sends frame, collects up to `expect` response frames (all that come
        within timeout when expect is 0: then returns as soon as it is quiet)."""
        self.sock.sendall(frame)
        return self.collect(frame, expect, timeout, quiet)

    def collect(self, frame, expect, timeout=2.0, quiet=False):
        got = []
        deadline = time.monotonic() + timeout
        self.sock.settimeout(0.05)
        while time.monotonic() < deadline and (expect == 0 or len(got) < expect):
            try:
                data = self.sock.recv(512)
            except socket.timeout:
                continue
            if not data:
                raise SystemExit("bus closed")
            got += self.parser.feed(data)
        if quiet:
            print("  > %d bytes\n  < %d frames" % (len(frame), len(got)))
        else:
            print("  > %s\n  < %s" % (frame.hex(" "), " | ".join(f.to_bytes().hex(" ") for f in got)))
        return got

    def split_frame(self, frame, at, pause, expect, timeout=0.5):
        """Sends frame[:at], pauses `pause` seconds, sends the rest."""
        self.sock.sendall(frame[:at])
        time.sleep(pause)
        self.sock.sendall(frame[at:])
        return self.collect(frame, expect, timeout)


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        raise SystemExit(1)


def wait_ping(bus, dev_id, seconds=10):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if bus.exchange(kmbus.ping(dev_id), 1, timeout=0.3):
            return True
    return False


def check_burst(bus, dev_id, count):
    """`count` pings to one servo, back to back in one TCP write: far more than
    the servo's 128-byte RX queue. A ping's answer is as long as the ping,
    so a servo at line rate answers each before the next one ends."""
    burst = kmbus.ping(dev_id) * count
    r = bus.exchange(burst, count, timeout=5.0 + count * 0.002, quiet=True)
    check(len(r) == count and all(f.id == dev_id and f.is_status for f in r),
          "host-sim line rate: a %d-byte burst of %d pings in one write, all %d answered (got %d)"
          % (len(burst), count, count, len(r)))


def check_gap(bus, dev_id, opts):
    """A ping whose bytes stop for longer than the gap in force, then go on:
    dropped (§7); the next whole ping is answered."""
    floor = GAP_FLOOR_DEFAULT_US if opts.gap_floor_us is None else opts.gap_floor_us
    gap_us = max(floor, 1000)  # parser: max(10 byte times, 1 ms) = 1 ms at 115200
    # Well past the gap: the servo must see the pause, and a host-sim
    # process stalled by a loaded machine reads both pieces together (then
    # there is no pause on its wire), so give it 50 ms of margin.
    pause = (gap_us + 50000) / 1e6
    r = bus.split_frame(kmbus.ping(dev_id), 3, pause, 0)
    check(r == [], "§7 a ping paused %.0f ms after 3 bytes (gap %.0f ms): dropped"
          % (pause * 1000, gap_us / 1000))
    r = bus.exchange(kmbus.ping(dev_id), 1)
    check(len(r) == 1 and r[0].id == dev_id, "§7 the next whole ping is answered")


def read_pos(bus, dev_id):
    r = bus.exchange(kmbus.read(dev_id, 0x46), 1, timeout=0.5, quiet=True)
    if len(r) != 1 or len(r[0].params) not in (2, 4):
        return None
    return int.from_bytes(r[0].params, "little", signed=True)


def wait_pos(bus, dev_id, lo, hi, seconds, seen):
    """Reads 0x46 until it is within [lo, hi]; seconds (wall clock) to that, or None."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        pos = read_pos(bus, dev_id)
        if pos is not None:
            seen.append(pos)
            if lo <= pos <= hi:
                return time.monotonic() - t0
    return None


def check_move(bus, dev_id):
    """§5.4: torque on, 0x65 to +45.0 deg in 500 ms; 0x46 read until it
    arrives, then 0x66 back to 0 at 180 deg/s, torque off. Wall-clock time
    on a shared machine: the bounds are loose (a stalled emulator integrates
    its plant over the stall); tests/unit/test_control_servo.c and
    tests/app/test_app_motion.c hold the tight figures in virtual time."""
    bus.exchange(kmbus.write(dev_id, 0x64, b"\x02"), 0, timeout=0.1)
    start = read_pos(bus, dev_id)
    t0 = time.monotonic()
    bus.exchange(kmbus.write(dev_id, 0x65, (450).to_bytes(2, "little", signed=True)
                             + (500).to_bytes(2, "little")), 0, timeout=0.02)
    seen = []
    near = wait_pos(bus, dev_id, 440, 460, 3.0, seen)
    arrived = None if near is None else near + 0.02
    settled = wait_pos(bus, dev_id, 445, 455, 2.0, seen) if near is not None else None
    if settled is not None:
        time.sleep(0.3)
        settled = wait_pos(bus, dev_id, 445, 455, 1.0, seen)  # holds there
    check(start is not None and abs(start) <= 5 and arrived is not None and settled is not None,
          "§5.4 0x65 +45.0 deg in 500 ms: 0x46 from %s, within 1 deg after %s ms (wall clock), "
          "holding at %s (highest read %s)"
          % (start, None if arrived is None else round(arrived * 1000), seen[-1] if seen else None,
             max(seen) if seen else None))
    check(arrived < 1.5, "§5.4 ... in about the requested time (under 1.5 s of wall clock)")
    t0 = time.monotonic()
    bus.exchange(kmbus.write(dev_id, 0x66, (0).to_bytes(2, "little") + (180).to_bytes(2, "little")),
                 0, timeout=0.02)
    back = wait_pos(bus, dev_id, -10, 10, 3.0, seen)
    check(back is not None, "§5.4 0x66 back to 0 at 180 deg/s: within 1 deg after %s ms"
          % (None if back is None else round((back + 0.02) * 1000)))
    check_motor_for_time(bus, dev_id)
    bus.exchange(kmbus.write(dev_id, 0x64, b"\x00"), 0, timeout=0.1)
    r = bus.exchange(kmbus.read(dev_id, 0x64), 1, timeout=0.5)
    check(len(r) == 1 and r[0].params == b"\x00", "§5.4 torque off: 0x64 reads 0")


def check_motor_for_time(bus, dev_id):
    """§5.4 0x70 (every variant): run at PWM 500 for 0.5 s, then brake.
    The shaft turns while it runs (0x46 rises, status bit 7 set) and stops
    by itself: two reads 200 ms apart agree once the time is up."""
    start = read_pos(bus, dev_id)
    control = 0x10 | 0x02  # p1 = time (0.1 s), p2 = PWM, brake after, positive
    bus.exchange(kmbus.write(dev_id, 0x70, bytes([control]) + (5).to_bytes(2, "little")
                             + (500).to_bytes(2, "little")), 0, timeout=0.02)
    time.sleep(0.2)
    mid = read_pos(bus, dev_id)
    r = bus.exchange(kmbus.read(dev_id, 0x01), 1, timeout=0.5)
    running = len(r) == 1 and r[0].params[:1] and r[0].params[0] & 0x80
    check(start is not None and mid is not None and mid > start + 50 and running,
          "§5.4 0x70 PWM 500 for 0.5 s: running (status %s), 0x46 from %s to %s after 200 ms "
          "(wall clock)" % (r[0].params.hex() if r else None, start, mid))
    time.sleep(1.0)
    a = read_pos(bus, dev_id)
    time.sleep(0.2)
    b = read_pos(bus, dev_id)
    r = bus.exchange(kmbus.read(dev_id, 0x01), 1, timeout=0.5)
    stopped = len(r) == 1 and r[0].params[:1] and not r[0].params[0] & 0x80
    check(a is not None and a == b and a > mid and stopped,
          "§5.4 0x70 ... stops by itself after its time: 0x46 %s then %s 200 ms later, "
          "status bit 7 clear (%s)" % (a, b, r[0].params.hex() if r else None))


def check_multi_move(bus, ids):
    """§4.2 + §5.4 on a bus: 0x83 turns all torques on, a second 0x83 sends
    each servo its own 0x65 target (one frame, all start together); every
    servo arrives at its own target, read back by 0x46; then 0x83 back to 0
    and torque off by broadcast."""
    targets = {i: t for i, t in zip(ids, (300, -300, 600))}

    def multi(addr, items):
        k = len(next(iter(items.values())))
        body = bytes([k]) + b"".join(bytes([i]) + d for i, d in items.items())
        return kmbus.encode_command(kmbus.ID_BROADCAST, kmbus.MULTI_WRITE, addr, body)

    bus.exchange(multi(0x64, {i: b"\x02" for i in ids}), 0, timeout=0.1)
    bus.exchange(multi(0x65, {i: t.to_bytes(2, "little", signed=True) + (500).to_bytes(2, "little")
                              for i, t in targets.items()}), 0, timeout=0.02)
    arrived = {}
    for i, t in targets.items():
        seen = []
        if wait_pos(bus, i, t - 10, t + 10, 3.0, seen) is not None:
            arrived[i] = seen[-1]
    check(len(arrived) == len(ids),
          "§4.2 0x83 of 0x65 (+30.0, -30.0, +60.0 deg in 500 ms): each servo arrived within "
          "1 deg of its own target: %s" % arrived)
    bus.exchange(multi(0x66, {i: (0).to_bytes(2, "little") + (180).to_bytes(2, "little") for i in ids}),
                 0, timeout=0.02)
    back = [i for i in ids if wait_pos(bus, i, -10, 10, 3.0, []) is not None]
    check(back == ids, "§4.2 0x83 of 0x66 back to 0: %s of %s arrived" % (back, ids))
    bus.exchange(kmbus.write(kmbus.ID_BROADCAST, 0x64, b"\x00"), 0, timeout=0.3)
    r = bus.exchange(kmbus.read(kmbus.ID_SUPER, 0x64), len(ids))
    check([f.params for f in r] == [b"\x00"] * len(ids), "§5.4 broadcast torque off: every 0x64 reads 0")


def smoke(backend, opts):
    bus = Bus(backend, [1], opts)
    try:
        r = bus.exchange(kmbus.ping(1), 1)
        check(len(r) == 1 and r[0].to_bytes() == kmbus.encode_status(1, 0), "§3 ping answered F9 F5 01 02 00 FC")
        r = bus.exchange(kmbus.read(1, 0x0B), 1)
        check(len(r) == 1 and r[0].params == bytes.fromhex("00000205"), "§5.1 0x0B reads 0x05020000 little-endian")
        check(bus.exchange(kmbus.write(1, 0x12, (350).to_bytes(2, "little")), 0, timeout=0.5) == [],
              "§3 write at response level 0: no answer")
        r = bus.exchange(kmbus.read(1, 0x12), 1)
        check(len(r) == 1 and r[0].params == (350).to_bytes(2, "little"), "§5.1 0x12 reads back 350")
        bad = bytearray(kmbus.ping(1))
        bad[-1] ^= 0xFF
        check(bus.exchange(bytes(bad), 0, timeout=0.5) == [], "§4 bad checksum: no answer")
        r = bus.exchange(kmbus.ping(1), 1)
        check(len(r) == 1 and r[0].status == 0x20, "§4 decision: next answer carries bit 5 after a bad checksum with our ID")
        check(bus.exchange(kmbus.write(1, 0x02, bytes.fromhex("E1E2E3E4")), 0, timeout=0.3) == [],
              "§3 restart: no answer")
        check(wait_ping(bus, 1), "answers again after the restart")
        r = bus.exchange(kmbus.read(1, 0x12), 1)
        check(len(r) == 1 and r[0].params == (350).to_bytes(2, "little"), "§5 user data 0x12 survived the restart")
        r = bus.exchange(kmbus.encode_command(1, 0x7F, 0x01), 1)
        check(len(r) == 1 and r[0].cmd == 0x7F and r[0].params == b"\x00",
              "extension read 0x7F 0x01: user data loaded from flash at boot")
        check_move(bus, 1)
        if backend == "host-sim":
            check_burst(bus, 1, 40)
            check_burst(bus, 1, 4096 // len(kmbus.ping(1)))
            check_gap(bus, 1, opts)
    finally:
        bus.close()


def bus_test(backend, opts):
    ids = [1, 2, 3]
    bus = Bus(backend, ids, opts)
    try:
        if backend == "qemu":
            bus.exchange(kmbus.write(kmbus.ID_BROADCAST, 0x10, (96).to_bytes(2, "little")), 0, timeout=0.3)
            bus.exchange(kmbus.write(kmbus.ID_BROADCAST, 0x02, bytes.fromhex("E1E2E3E4")), 0, timeout=0.3)
            check(all(wait_ping(bus, i) for i in ids), "all servos back at 9600 baud (set by broadcast)")
        r = bus.exchange(kmbus.ping(kmbus.ID_SUPER), 3)
        check([f.id for f in r] == ids and all(f.is_status for f in r), "§3 super-ID ping: three answers in ID order")
        bus.exchange(kmbus.write(kmbus.ID_BROADCAST, 0x12, (400).to_bytes(2, "little")), 0, timeout=0.5)
        r = bus.exchange(kmbus.read(kmbus.ID_SUPER, 0x12), 3)
        check([f.id for f in r] == ids and all(f.params == (400).to_bytes(2, "little") for f in r),
              "§3 broadcast write changed all three (read back with the super ID)")
        # A response from "servo 2" whose value bytes hold a whole ping to
        # servo 1: every servo must skip it whole (§2), nobody answers.
        fake = kmbus.encode_response(2, kmbus.READ, 0x0A, kmbus.ping(1))
        check(bus.exchange(fake, 0, timeout=0.8) == [], "§2 a response frame with F9 FF inside is skipped whole")
        r = bus.exchange(kmbus.ping(1), 1)
        check(len(r) == 1 and r[0].id == 1 and r[0].status == 0, "servo 1 still answers, status clean")
        check_move(bus, 2)
        check_multi_move(bus, ids)
        if backend == "host-sim":
            # the other two servos hear the burst and all 40 answers too
            check_burst(bus, 2, 40)
            check_gap(bus, 3, opts)
    finally:
        bus.close()


def motor_speed(bus, dev_id, dps):
    return bus.exchange(kmbus.write(dev_id, 0x6F, dps.to_bytes(2, "little", signed=True)), 0,
                        timeout=0.05)


def encoder(backend, opts):
    """§6 both variants: the encoder product (servo-bus --product encoder)
    names itself, takes 0x6F and turns past one revolution (no end stops,
    0x46 multi-turn), stops on 0x6F 0; the pot product refuses 0x6F with
    status bit 6 and does not move. Wall clock: about 3 s in all."""
    opts.product = "encoder"
    bus = Bus(backend, [1], opts)
    try:
        r = bus.exchange(kmbus.read(1, 0x0A), 1)
        check(len(r) == 1 and r[0].params.rstrip(b"\0") == b"KM-SIM-ENCODER",
              "§5.1 0x0A names the encoder product KM-SIM-ENCODER (%r)"
              % (r[0].params if r else None))
        start = read_pos(bus, 1)
        motor_speed(bus, 1, 360)
        r = bus.exchange(kmbus.ping(1), 1)
        check(len(r) == 1 and not r[0].status & 0x40, "§5.4 0x6F 360 deg/s accepted: status bit 6 clear (%s)"
              % (hex(r[0].status) if r else None))
        seen = []
        passed = wait_pos(bus, 1, 3700, 2 ** 31 - 1, 3.0, seen)
        check(start is not None and abs(start) <= 5 and passed is not None
              and all(b >= a for a, b in zip(seen, seen[1:])),
              "§5.4 0x6F: 0x46 from %s increases steadily past 360.0 deg (370.0 after %s ms, "
              "wall clock; last read %s)" % (start, None if passed is None else round(passed * 1000),
                                              seen[-1] if seen else None))
        motor_speed(bus, 1, 0)
        time.sleep(0.3)
        a = read_pos(bus, 1)
        time.sleep(0.2)
        b = read_pos(bus, 1)
        check(a is not None and a == b and a >= 3700,
              "§5.4 0x6F 0 stops it: 0x46 %s then %s 200 ms later" % (a, b))
        # The shaft is physics: a restart of the MCU leaves it where it is.
        # The encoder is absolute within one turn and the turn count is RAM,
        # so after the restart 0x46 is the angle within one turn.
        check(bus.exchange(kmbus.write(1, 0x02, bytes.fromhex("E1E2E3E4")), 0, timeout=0.3) == [],
              "§3 restart: no answer")
        check(wait_ping(bus, 1), "answers again after the restart")
        pos = read_pos(bus, 1)
        check(pos is not None and abs(pos - a % 3600) <= 1,
              "§6 after a restart the multi-turn position reads %s: the shaft stayed at %.1f deg, "
              "read as its angle within one turn (%.1f deg; the turn count is RAM)"
              % (pos, a / 10, (a % 3600) / 10))
    finally:
        bus.close()
    opts.product = "pot"
    bus = Bus(backend, [1], opts)
    try:
        r = bus.exchange(kmbus.read(1, 0x0A), 1)
        check(len(r) == 1 and r[0].params.rstrip(b"\0") == b"KM-SIM-P135",
              "§5.1 0x0A names the pot product KM-SIM-P135")
        motor_speed(bus, 1, 360)
        r = bus.exchange(kmbus.ping(1), 1)
        check(len(r) == 1 and r[0].status & 0x40, "§6 the pot product refuses 0x6F: the next ping has "
              "status bit 6 (%s)" % (hex(r[0].status) if r else None))
        time.sleep(0.3)
        pos = read_pos(bus, 1)
        check(pos is not None and abs(pos) <= 5, "§6 ... and nothing moves: 0x46 %s" % pos)
    finally:
        bus.close()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("which", choices=["smoke", "bus", "encoder"])
    ap.add_argument("--backend", choices=["qemu", "host-sim"], required=True)
    ap.add_argument("--gap-floor-us", type=int, help="passed to tools/servo-bus")
    ap.add_argument("--build-dir", help="passed to tools/servo-bus")
    a = ap.parse_args()
    {"smoke": smoke, "bus": bus_test, "encoder": encoder}[a.which](a.backend, a)
    print("%s %s: all checks passed" % (a.backend, a.which))


if __name__ == "__main__":
    main()
