#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Run the conformance suite on an emulated bus (what CTest runs).

    run_on_bus.py --backend host-sim|qemu|g031 [--ids 1,2,3] [--bus-baud N]
                  [--slot-timing auto|realtime|plain] [--slot-floor-us N]
                  [--slow-baud N --slow NAME...] [--] SUITE-ARGS...

Starts sim/bus/servo-bus on a free port (sim/bus/simbus.py), runs
conformance.py --bus rfc2217:127.0.0.1:PORT@BAUD (the hub as a serial port
whose baud the suite sets and changes) with the same
--ids and SUITE-ARGS, and always stops the bus (SIGTERM, then SIGKILL),
also when the suite fails, times out or this wrapper is interrupted.

Every check SUITE-ARGS name (their --only/--exclude, as conformance.py
--list gives them; all 183 without) runs, each exactly once: the passes
get the names one by one (--only =NAME). The closing lines count the
results against those names: a named check with no result line, or with
two, is a FAIL ("not run: ..."), as is a result for a check not named; each
SKIP is listed with its reason ("# skipped NAME: why"), and the last line
is "total: N passed, M failed, K skipped" over every named check. Exit
status 1 on any failure (a check not run included) or when the bus does
not come up.

--slot-floor-us N: passed to servo-bus (every super-ID and 0x82 answer slot
of the emulated boards at least N us; the suite checks the answers'
order, not their times). CTest gives QEMU 20000 (tests/conformance.cmake).

--bus-baud N: before the suite, every servo is switched to N baud over the
protocol (broadcast write 0x10, broadcast restart), as tests/bus/bus_check.py
does for QEMU, whose emulated UART has no line rate but whose super-ID slots
follow the servos' baud (docs/protocol-decisions.md "Super-ID answer slots").

--virtual-time (g031 only): servo-bus --clock-file keeps the virtual time
of the servos, and each pass runs under sim/g031/vclock.py, so every
timeout and pause of the suite counts that time, not the host's
(docs/virtual-g031.md "Virtual time for the master"); no --time-scale is
needed however slow the emulator.

--slot-timing: "realtime" runs the bus with servo-bus --realtime (hub and
emulators under SCHED_FIFO) and the suite under SCHED_FIFO below them, so
emulated super-ID and 0x82 answers keep the real slot rule at 115200
(docs/protocol-decisions.md "Answer slots on emulated buses"): every named
check then runs in one pass at the bus baud, --slow included. "auto" (the
default) does so when the host allows SCHED_FIFO (root, or an rtprio
limit), else "plain" (servo-bus --no-realtime).

--slow-baud N --slow NAME...: on a plain bus only, two passes on the same
bus: first every named check that NAME (as --only: exact, glob, prefix or
=NAME) does not match, then every servo is switched to N baud and the
named checks it matches run. For the checks that need super-ID answers in
slot order: an emulated servo starts its answer when the host schedules
it, so with three emulators and the hub sharing two cores the order of
slots 0.7 ms apart (115200 baud) is not kept under plain scheduling, while
8.3 ms apart (9600 baud) it is (tests/conformance/README.md).
"""
import argparse
import os
import re
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SUITE = os.path.join(HERE, "conformance.py")
import simbus  # noqa: E402  (sim/bus on PYTHONPATH)
VCLOCK = os.path.join(simbus.REPO, "sim", "g031", "vclock.py")
import wire as W  # noqa: E402
import conformance as S  # noqa: E402  (its check selection: S.matches)


def switch_baud(port, ids, baud, old):
    """Servos and master from `old` to `baud` (the hub models the line
    rate: sim/bus/servo-bus "Baud"), over RFC 2217 as over a serial port."""
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


def split_selection(suite):
    """(the suite's --only/--exclude patterns as conformance.py arguments,
    its other arguments)."""
    sp = argparse.ArgumentParser(add_help=False, allow_abbrev=False)
    sp.add_argument("--only", action="append", default=[])
    sp.add_argument("--exclude", action="append", default=[])
    sel, rest = sp.parse_known_args(suite)
    return sum((["--only", x] for x in sel.only), []) + sum((["--exclude", x] for x in sel.exclude), []), rest


def named_checks(selection):
    """The names of the checks conformance.py selects with these
    --only/--exclude arguments, in suite order (its --list)."""
    out = subprocess.run([sys.executable, SUITE, "--list"] + selection, stdout=subprocess.PIPE,
                         text=True, check=True).stdout.splitlines()
    return [line.split()[0] for line in out[:-1]]


def plan_passes(names, realtime, bus_baud, slow_baud, slow):
    """[(baud or None, [check names])]: every named check in one pass at the
    bus baud on a SCHED_FIFO bus (or without --slow-baud); on a plain bus,
    the checks --slow matches in a second pass at --slow-baud."""
    late = [n for n in names if any(S.matches(n, p) for p in slow)]
    if realtime or not slow_baud or not late:
        return [(bus_baud, names)]
    return [(bus_baud, [n for n in names if n not in late]), (slow_baud, late)]


RESULT = re.compile(r"(PASS|FAIL|SKIP) (\S+?)(?:: (.*))?$")


def tally(names, lines):
    """Counts the suite's result lines against the checks named: [passed,
    failed, skipped], the skips as (name, reason), and a FAIL line for each
    named check without exactly one result (not run, or reported twice) and
    each result of a check not named."""
    counts, skips, problems = [0, 0, 0], [], []
    seen = {}
    for line in lines:
        m = RESULT.match(line)
        if not m:
            continue
        kind, name, why = m.groups()
        seen[name] = seen.get(name, 0) + 1
        if name not in names:
            problems.append("FAIL %s: ran, but not one of the checks named" % name)
            continue
        counts["PASS FAIL SKIP".split().index(kind)] += 1
        if kind == "SKIP":
            skips.append((name, why))
    for name in names:
        if seen.get(name, 0) == 0:
            problems.append("FAIL %s: not run: the suite printed no result for it" % name)
        elif seen[name] > 1:
            problems.append("FAIL %s: %d results for one check" % (name, seen[name]))
    counts[1] += len(problems)
    return counts, skips, problems


def run_pass(port, ids, baud, names, args, clock=None):
    """One conformance.py run on the bus at `baud` over exactly `names`
    (on the bus's virtual time with `clock`, sim/g031/vclock.py); its
    output lines (echoed), or None when it ended without its summary."""
    on_clock = [VCLOCK, clock] if clock else []
    out = subprocess.run([sys.executable] + on_clock + [SUITE, "--bus", "rfc2217:127.0.0.1:%d@%d" % (port, baud),
                          "--ids", ids] + args + sum((["--only", "=" + n] for n in names), []),
                         stdout=subprocess.PIPE, text=True)
    sys.stdout.write(out.stdout)
    sys.stdout.flush()
    lines = out.stdout.strip().splitlines()
    if not lines or not SUMMARY.match(lines[-1]) or out.returncode not in (0, 1):
        print("FAIL suite: exit %d without its summary line" % out.returncode, flush=True)
    return lines


SUMMARY = re.compile(r"(\d+) passed, (\d+) failed, (\d+) skipped$")


def run_suite(port, a, realtime, t0):
    """Every pass, then the closing lines: each skip with its reason and
    "total: N passed, M failed, K skipped" over every check named. Exit
    status: 1 on any failure, a check not run included."""
    selection, rest = split_selection([x for x in a.suite if x != "--"])
    names = named_checks(selection)
    print("# %d checks named" % len(names), flush=True)
    if not names:
        print("FAIL suite: the --only/--exclude arguments name no check", flush=True)
        return 1
    lines, crashed, now = [], False, 115200
    for baud, group in plan_passes(names, realtime, a.bus_baud, a.slow_baud, a.slow):
        if baud and baud != now:
            switch_baud(port, [int(x) for x in a.ids.split(",")], baud, now)
            now = baud
            print("# bus: servos switched to %d baud (%d checks)" % (baud, len(group)), flush=True)
        out = run_pass(port, a.ids, now, group, rest, a.clock)
        crashed |= not out or not SUMMARY.match(out[-1])
        lines += out
    counts, skips, problems = tally(names, lines)
    print("# run time %.1f s" % (time.monotonic() - t0))
    for line in problems:
        print(line)
    for name, why in skips:
        print("# skipped %s: %s" % (name, why))
    print("total: %d passed, %d failed, %d skipped" % tuple(counts), flush=True)
    return 1 if counts[1] or crashed else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--backend", required=True, choices=("host-sim", "qemu", "g031"))
    ap.add_argument("--ids", default="1,2,3")
    ap.add_argument("--bus-baud", type=int)
    ap.add_argument("--gap-floor-us", type=int)
    ap.add_argument("--slot-floor-us", type=int)
    ap.add_argument("--slow-baud", type=int)
    ap.add_argument("--slow", action="append", default=[])
    ap.add_argument("--slot-timing", choices=("auto", "realtime", "plain"), default="auto")
    ap.add_argument("--image", help="passed to servo-bus: the servo image (default: the backend's)")
    ap.add_argument("--virtual-time", action="store_true",
                    help="g031 only: the suite's waits in the bus's virtual time (servo-bus --clock-file)")
    ap.add_argument("suite", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    if a.virtual_time and a.backend != "g031":
        ap.error("--virtual-time: the g031 backend only (the others run in real time)")
    clock_dir = tempfile.TemporaryDirectory(prefix="run-on-bus-") if a.virtual_time else None
    a.clock = os.path.join(clock_dir.name, "clock") if clock_dir else None
    argv = ["--ids", a.ids, "--backend", a.backend, "--timeout", "30"]
    realtime = a.slot_timing == "realtime" or (a.slot_timing == "auto" and realtime_allowed())
    if realtime:
        # Below the hub (20) and the servos (10); the suite inherits it.
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(5))
        argv.append("--realtime")
    else:
        argv.append("--no-realtime")  # servo-bus's default would be SCHED_FIFO where allowed
    print("# slot timing: %s" % ("SCHED_FIFO bus and suite, every check at the bus baud" if realtime
                                 else "plain scheduling"), flush=True)
    if a.gap_floor_us is not None:
        argv += ["--gap-floor-us", str(a.gap_floor_us)]
    if a.image:
        argv += ["--image", a.image]
    if a.clock:
        argv += ["--clock-file", a.clock]
        print("# virtual time: the suite's timeouts and pauses count the servos' time", flush=True)
    if a.slot_floor_us is not None:
        argv += ["--slot-floor-us", str(a.slot_floor_us)]
        print("# slot floor: every super-ID and 0x82 answer slot at least %d us (servo-bus "
              "--slot-floor-us)" % a.slot_floor_us, flush=True)
    t0 = time.monotonic()

    def stop(*_):
        raise KeyboardInterrupt
    signal.signal(signal.SIGTERM, stop)
    try:
        with simbus.ServoBusProcess(argv) as bus:
            print("# bus: %s, %s servos %s, up in %.1f s" % (bus.ready_line, a.backend, a.ids,
                                                             time.monotonic() - t0), flush=True)
            return run_suite(bus.port, a, realtime, t0)
    except simbus.NotReady as e:
        print(str(e), flush=True)
        return 1
    except KeyboardInterrupt:
        return 1

if __name__ == "__main__":
    sys.exit(main())
