#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""KINGMAX serial servo protocol v5.2.0 conformance suite (docs/protocol.md).

    conformance.py --bus tcp:127.0.0.1:7000@115200 --ids 1,2,3
    conformance.py --bus serial:/dev/ttyUSB0@115200 --ids 1,2,3
    conformance.py --bus pty:/dev/pts/5 --ids 1
    conformance.py --list                      names, basis, what each checks
    conformance.py ... --only 'reg.*' --only cmd.ping   (exact name, glob or prefix;
                                               =NAME: that name alone)
    conformance.py ... --exclude super. --exclude load   (the same, left out)
    conformance.py ... --load 100000           the full load run (default 100000)

Talks to servos over the bus alone, so it runs unchanged against real
hardware. Expectations come from docs/protocol.md (spec.py);
checks named "decision:..." test a point the spec leaves open and
docs/protocol-decisions.md settles. Output: one line per check, "PASS name",
"FAIL name: why" or "SKIP name: why" (a check that cannot be observed on this
bus, e.g. a baud change on a TCP bus; after a bus error, every check left:
"SKIP name: not run: the bus failed in CHECK"), lines starting "#" are
figures; then "N passed, M failed, K skipped", one result per check
selected. Exit status 1 on any failure.

The servos under test (--ids) must answer on the bus; other servos may share
it. Checks restore what they change (ID, baud, limits, modes), so the suite
can be run again on the same bus. Status bits 5/6 of a write at response
level 0 are read from the next ping (§4 "cleared on the next command").
"""
import argparse
import fnmatch
import os
import sys
import time
import traceback

HERE = os.path.dirname(os.path.abspath(__file__))
import ctx as C  # noqa: E402
import wire as W  # noqa: E402
from kmx.errors import KmxError  # noqa: E402
import checks_commands  # noqa: E402,F401  (each module registers its checks)
import checks_registers  # noqa: E402,F401
import checks_status  # noqa: E402,F401
import checks_bus  # noqa: E402,F401
import checks_restart  # noqa: E402,F401
import checks_bad  # noqa: E402,F401
import checks_load  # noqa: E402,F401


def parse_ids(text):
    ids = [int(x, 0) for x in text.split(",") if x.strip()]
    if not ids or len(set(ids)) != len(ids) or any(not 0 <= i <= 250 for i in ids):
        raise argparse.ArgumentTypeError("IDs must be distinct, in 0..250")
    return ids


def matches(name, pattern):
    """--only/--exclude: "=NAME" that name alone, else the exact name, a glob or a prefix."""
    if pattern.startswith("="):
        return name == pattern[1:]
    return name == pattern or fnmatch.fnmatchcase(name, pattern) or name.startswith(pattern)


def selected(checks, patterns):
    """The checks any of the patterns match, in suite order (all without patterns)."""
    if not patterns:
        return list(checks)
    return [c for c in checks if any(matches(c.name, p) for p in patterns)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 epilog=__doc__[__doc__.index("Talks"):],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bus", help="tcp:HOST:PORT[@BAUD], pty:/dev/pts/N or serial:DEV@BAUD "
                    "(tcp @BAUD: the master keeps to that line rate, see wire.py)")
    ap.add_argument("--ids", type=parse_ids, default=[1, 2, 3], help="servos under test (1,2,3)")
    ap.add_argument("--list", action="store_true", help="list the checks and exit")
    ap.add_argument("--only", action="append", default=[], metavar="NAME",
                    help="run only this check (exact name, glob, or prefix; =NAME: that name "
                    "alone); repeatable")
    ap.add_argument("--exclude", action="append", default=[], metavar="NAME",
                    help="leave this check out (as --only); repeatable")
    ap.add_argument("--load", type=int, default=100000, metavar="N",
                    help="transactions in the load run (default 100000)")
    ap.add_argument("--timeout", type=float, default=0.5, help="s to wait for a due answer")
    ap.add_argument("--quiet-ms", type=float, default=80.0,
                    help="ms of silence taken as 'no answer' (default 80)")
    ap.add_argument("--pause-ms", type=float, default=150.0,
                    help="ms of silence inside a frame that drops it, longer than any gap rule "
                    "(default 150)")
    ap.add_argument("--restart-s", type=float, default=10.0,
                    help="s a servo may take to answer after a restart (default 10)")
    ap.add_argument("--time-scale", type=float, default=1.0, metavar="F",
                    help="multiply every wait for an answer or a quiet bus by F (default 1): for "
                    "emulated servos slower than real time (servo-bus --backend g031)")
    ap.add_argument("-v", "--verbose", action="store_true", help="check progress on stderr")
    opts = ap.parse_args(argv)
    opts.log = (lambda m: print("  " + m, file=sys.stderr, flush=True)) if opts.verbose \
        else (lambda m: None)

    checks = selected(C.CHECKS, opts.only)
    if opts.exclude:
        drop = set(id(c) for c in selected(checks, opts.exclude))
        checks = [c for c in checks if id(c) not in drop]
    if opts.list:
        for c in checks:
            print("%-48s %-28s %s" % (c.name, c.basis, c.doc.splitlines()[0] if c.doc else ""))
        print("%d checks" % len(checks))
        return 0
    if not opts.bus:
        ap.error("--bus is required (or --list)")
    if not checks:
        ap.error("--only %s matches no check (see --list)" % " ".join(opts.only))

    try:
        wire = W.Wire(opts.bus, opts.time_scale)
    except KmxError as e:
        print("FAIL bus: %s" % e)
        return 1
    ctx = C.Ctx(wire, opts.ids, opts)
    ctx.transport = wire  # .kind, .can_set_baud
    passed = failed = skipped = 0
    t_all = time.monotonic()
    try:
        for c in checks:
            t0 = time.monotonic()
            bad0 = wire.bad_frames
            wire.stale = []
            try:
                wire.drain(0.01)
                c.fn(ctx)
                stray = wire.drain(ctx.quiet)
                if stray:
                    raise C.Fail("unexpected frame(s) after the check: " +
                                 " | ".join(C.hexs(f.to_bytes()) for f in stray))
                if wire.stale:
                    raise C.Fail("late frame(s), answers to an earlier request: " +
                                 " | ".join(C.hexs(f.to_bytes()) for f in wire.stale))
                if wire.bad_frames != bad0:
                    raise C.Fail("%d frame(s) with a bad checksum or length on the bus"
                                 % (wire.bad_frames - bad0))
                print("PASS " + c.name, flush=True)
                passed += 1
            except C.Skip as e:
                print("SKIP %s: %s" % (c.name, e), flush=True)
                skipped += 1
            except C.Fail as e:
                print("FAIL %s: %s" % (c.name, e), flush=True)
                failed += 1
                wire.drain(ctx.quiet)
            except (OSError, ConnectionError, KmxError) as e:
                print("FAIL %s: bus error: %s" % (c.name, e), flush=True)
                failed += 1
                for left in checks[checks.index(c) + 1:]:
                    print("SKIP %s: not run: the bus failed in %s" % (left.name, c.name), flush=True)
                    skipped += 1
                break
            except Exception as e:  # a bug in the check itself: say where
                print("FAIL %s: error in the check: %r" % (c.name, e), flush=True)
                traceback.print_exc(file=sys.stderr)
                failed += 1
                wire.drain(ctx.quiet)
            opts.log("%s: %.2f s" % (c.name, time.monotonic() - t0))
    finally:
        wire.close()
    print("# %d checks in %.1f s" % (passed + failed + skipped, time.monotonic() - t_all))
    print("%d passed, %d failed, %d skipped" % (passed, failed, skipped))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
