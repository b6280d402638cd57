#!/usr/bin/python3
"""Run the conformance suite on an emulated bus (what CTest runs).

    run_on_bus.py --backend host-sim|qemu [--ids 1,2,3] [--bus-baud N]
                  [--slot-timing auto|realtime|plain]
                  [--slow-baud N --slow NAME...] [--] SUITE-ARGS...

Starts tools/servo-bus on a free port (--port 0: it prints the port in its
"ready" line), runs conformance.py --bus rfc2217:127.0.0.1:PORT@BAUD (the
hub as a serial port whose baud the suite sets and changes) with the same
--ids and SUITE-ARGS, and always stops the bus (SIGTERM, then SIGKILL),
also when the suite fails, times out or this wrapper is interrupted.
Exit status: the suite's, or 1 when the bus does not come up.

--bus-baud N: before the suite, every servo is switched to N baud over the
protocol (broadcast write 0x10, broadcast restart), as tests/bus/bus_check.py
does for QEMU, whose emulated UART has no line rate but whose super-ID slots
follow the servos' baud (docs/protocol-decisions.md "Super-ID answer slots").

--slot-timing: "realtime" runs the bus with servo-bus --realtime (hub and
emulators under SCHED_FIFO) and the suite under SCHED_FIFO below them, so
emulated super-ID and 0x82 answers keep the real slot rule at 115200
(docs/protocol-decisions.md "Answer slots on emulated buses"); "auto" (the
default) does so when the host allows SCHED_FIFO (root, or an rtprio
limit), else "plain". --slow-baud applies only to a plain bus.

--slow-baud N --slow NAME...: two passes on the same bus (plain bus only). The suite first
runs without the checks NAME (exact, glob or prefix, as --only), then every
servo is switched to N baud and the suite runs those checks alone. For the
checks that need super-ID answers in slot order: an emulated servo starts
its answer when the host schedules it, so with three emulators and the hub
sharing two cores the order of slots 0.7 ms apart (115200 baud) is not
kept, while 8.3 ms apart (9600 baud) it is (tests/conformance/README.md).
The last line sums both passes: "N passed, M failed, K skipped".
"""
import argparse
import os
import re
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import wire as W  # noqa: E402


def switch_baud(port, ids, baud, old):
    """Servos and master from `old` to `baud` (the hub models the line
    rate: tools/servo-bus "Baud"), over RFC 2217 as over a serial port."""
    t = W.Wire("rfc2217:127.0.0.1:%d@%d" % (port, old))
    try:
        kmbus = W.fr
        t.send(kmbus.write(0xFE, 0x10, (baud // 100).to_bytes(2, "little")))
        time.sleep(0.3)
        t.send(kmbus.write(0xFE, 0x02, bytes([0xE1, 0xE2, 0xE3, 0xE4])))
        time.sleep(0.05)
        t.set_baud(baud)
        time.sleep(0.25)
        for i in ids:
            end = time.monotonic() + 20
            while not t.transact(kmbus.ping(i), 1, 0.3):
                if time.monotonic() > end:
                    raise SystemExit("servo %d lost after switching to %d baud" % (i, baud))
        t.drain(0.2)
    finally:
        t.close()


def realtime_allowed():
    """True when this host lets a process enter SCHED_FIFO."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))
    except (PermissionError, OSError, AttributeError):
        return False
    os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--backend", required=True, choices=("host-sim", "qemu"))
    ap.add_argument("--ids", default="1,2,3")
    ap.add_argument("--bus-baud", type=int)
    ap.add_argument("--gap-floor-us", type=int)
    ap.add_argument("--slow-baud", type=int)
    ap.add_argument("--slow", action="append", default=[])
    ap.add_argument("--slot-timing", choices=("auto", "realtime", "plain"), default="auto")
    ap.add_argument("suite", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    argv = [sys.executable, os.path.join(ROOT, "tools", "servo-bus"), "--ids", a.ids, "--port", "0",
            "--backend", a.backend, "--timeout", "30"]
    realtime = a.slot_timing == "realtime" or (a.slot_timing == "auto" and realtime_allowed())
    if realtime:
        # Below the hub (20) and the servos (10); the suite inherits it.
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(5))
        argv.append("--realtime")
        a.slow_baud = None
    else:
        argv.append("--no-realtime")  # servo-bus's default would be SCHED_FIFO where allowed
    print("# slot timing: %s" % ("SCHED_FIFO bus and suite, every check at the bus baud" if realtime
                                 else "plain scheduling"), flush=True)
    if a.gap_floor_us is not None:
        argv += ["--gap-floor-us", str(a.gap_floor_us)]
    t0 = time.monotonic()
    # Same process group as this wrapper: a CTest timeout that kills the
    # group takes the bus (and its servos) with it.
    bus = subprocess.Popen(argv, stdout=subprocess.PIPE, text=True)

    def stop(*_):
        raise KeyboardInterrupt
    signal.signal(signal.SIGTERM, stop)
    try:
        line = bus.stdout.readline().strip()
        if not line.startswith("ready "):
            print("servo-bus did not get ready: %r" % line, flush=True)
            return 1
        port = int(line.rsplit(":", 1)[1])
        print("# bus: %s, %s servos %s, up in %.1f s" % (line, a.backend, a.ids, time.monotonic() - t0),
              flush=True)
        ids = [int(x) for x in a.ids.split(",")]
        suite = [x for x in a.suite if x != "--"]
        passes = [(a.bus_baud, suite + sum((["--exclude", p] for p in a.slow), []))]
        if a.slow_baud and a.slow:
            passes.append((a.slow_baud, suite + sum((["--only", p] for p in a.slow), [])))
        totals = [0, 0, 0]
        now = 115200
        for baud, args in passes:
            if baud and baud != now:
                switch_baud(port, ids, baud, now)
                now = baud
                print("# bus: servos switched to %d baud" % baud, flush=True)
            out = subprocess.run([sys.executable, os.path.join(HERE, "conformance.py"),
                                  "--bus", "rfc2217:127.0.0.1:%d@%d" % (port, now),
                                  "--ids", a.ids] + args, stdout=subprocess.PIPE, text=True)
            sys.stdout.write(out.stdout)
            sys.stdout.flush()
            last = (out.stdout.strip().splitlines() or [""])[-1]
            m = re.match(r"(\d+) passed, (\d+) failed, (\d+) skipped", last)
            if not m or out.returncode not in (0, 1):
                print("FAIL suite: exit %d, no summary line" % out.returncode, flush=True)
                return 1
            totals = [t + int(x) for t, x in zip(totals, m.groups())]
        if len(passes) > 1:
            print("# both passes:")
            print("%d passed, %d failed, %d skipped" % tuple(totals), flush=True)
        return 1 if totals[1] else 0
    except KeyboardInterrupt:
        return 1
    finally:
        if bus.poll() is None:
            bus.terminate()
            try:
                bus.wait(10)
            except subprocess.TimeoutExpired:
                bus.kill()
                bus.wait()
        print("# run time %.1f s" % (time.monotonic() - t0), flush=True)


if __name__ == "__main__":
    sys.exit(main())
