#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Ctrl-C at random moments of sim/bus/servo-bus's start-up must never leave a
servo process (QEMU or host-sim) behind (issue 11 item 4).

    tests/tools/ctrl_c_check.py [--backend host-sim|qemu] [--runs N] [--seed S]
                                [--signal INT|TERM] [--ids 1,2,3] [--demo]

--demo interrupts tools/servo-demo instead (its build, bus and kmx session;
its whole process group gets the signal, as from a terminal).

Each run starts servo-bus as a terminal's foreground job (its own process
group, SIGINT and SIGTERM at their defaults and unblocked whatever this
script got), sends the group SIGINT (as a terminal's Ctrl-C does) after a
delay drawn uniformly from 0 to 1.3 x the time a first, untouched start
took to print "ready", waits for it to exit and then looks for processes
left over, by PID: this script makes itself the child subreaper
(prctl PR_SET_CHILD_SUBREAPER), so any servo process that outlives
servo-bus is re-parented to it, and every process whose parent is this
script after servo-bus has exited is a leftover (it is killed, and the run
fails). Also fails a run when servo-bus exits with another status than 0,
prints a traceback or is still running 30 s after the signal (a signal it
lost: it would have printed "ready" and served the bus). A ready line
written after the signal was sent is counted apart ("ready raced the
signal"): the signal came after servo-bus's final check, in the moment
before the line went out, and the bus then stops at once. A SIGINT that
comes before servo-bus's handlers are in place is at times printed by
Python with its KeyboardInterrupt and then dropped, and servo-bus runs all
the same, never having seen it (seen: while the interpreter checks
whether argv[0] is an import path entry, "Failed checking if argv[0] is an
import path entry", and in an import lock's weakref callback, "Exception
ignored in"): once servo-bus's own lines follow such a KeyboardInterrupt,
the group is signalled once more, as a user presses Ctrl-C again, and the
run counted apart; it must still end with status 0 and nothing left. A failed run prints servo-bus's whole stderr (its
servos' too). Prints one line per run and a summary "N runs, M left processes behind or failed (...)";
exit status 1 if any did."""
import argparse
import ctypes
import os
import random
import re
import signal
import select
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PR_SET_CHILD_SUBREAPER = 36
# A traceback frame in servo-bus's own code after its signal handlers are in
# place (line 0 is the interpreter compiling it; before the handlers, the
# "import signal" itself).
SERVO_BUS_FRAME = re.compile(r'File ".*servo-bus", line (\d+)')
# CPython's whole stderr when a SIGINT interrupts it while it sets up the
# script's __main__ module, before the script's first line (exit 1).
PYTHON_NO_LOADER = "python: failed to set __main__.__loader__"


def handlers_line():
    with open(os.path.join(REPO, "sim", "bus", "servo-bus")) as f:
        for n, line in enumerate(f, 1):
            if line.strip().startswith("signal.signal(signal.SIGTERM"):
                return n
    raise SystemExit("sim/bus/servo-bus installs no SIGTERM handler at the top")


def after_handlers(frames, first):
    return any(int(m.group(1)) > first for m in map(SERVO_BUS_FRAME.search, frames) if m)


def children():
    """PIDs of live processes whose parent is this one (zombies reaped first)."""
    me = os.getpid()
    out = []
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open("/proc/%s/stat" % name) as f:
                stat = f.read()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2:].split()
        state, ppid = fields[0], int(fields[1])
        if ppid != me:
            continue
        if state == "Z":
            try:
                os.waitpid(int(name), os.WNOHANG)
            except ChildProcessError:
                pass
            continue
        out.append(int(name))
    return out


def command_of(pid):
    try:
        with open("/proc/%d/cmdline" % pid, "rb") as f:
            return f.read().replace(b"\0", b" ").decode(errors="replace").strip()
    except OSError:
        return "?"


def as_a_terminal_job():
    """In the child before exec: SIGINT and SIGTERM at their defaults and
    unblocked, as a terminal's foreground job gets them, whatever this
    script was started with (a shell's background job ignores SIGINT, and
    an ignored signal sent before servo-bus installs its handlers would be
    lost: not the launcher's doing)."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})


def start(argv, errfile):
    # stderr to a file: a leftover servo holding a pipe open would block the reader
    errfile.seek(0)
    errfile.truncate()
    # its own process group, signalled whole, as a terminal's Ctrl-C does
    return subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=errfile, text=True, start_new_session=True,
                            preexec_fn=as_a_terminal_job)


def ready_written(p):
    """True when servo-bus has written something (its ready line) to stdout."""
    return bool(select.select([p.stdout], [], [], 0)[0])


def text_so_far(errfile):
    """What servo-bus and its servos wrote to `errfile` so far, read without
    moving the file offset they share with this process (a seek here would
    make their next writes overwrite what is there)."""
    chunks, at = [], 0
    while True:
        chunk = os.pread(errfile.fileno(), 65536, at)
        if not chunk:
            return b"".join(chunks).decode(errors="replace")
        chunks.append(chunk)
        at += len(chunk)


def dropped_by_python(text):
    """True when the interpreter printed the KeyboardInterrupt of a SIGINT
    that came before servo-bus's handlers and then dropped it, going on to
    run servo-bus, which never saw the signal: its own lines follow."""
    at = text.find("KeyboardInterrupt")
    return at >= 0 and "servo-bus: " in text[at:]


def finish(p, errfile, sig, timeout=30):
    """Waits for servo-bus to exit, signalling its group once more if Python
    dropped the first signal (as a user presses Ctrl-C again); (stdout,
    stderr text, timed out, signalled again)."""
    timed_out = again = False
    end = time.monotonic() + timeout
    while p.poll() is None:
        if time.monotonic() > end:
            timed_out = True
            p.kill()
            break
        if not again and dropped_by_python(text_so_far(errfile)):
            again = True
            os.killpg(p.pid, sig)
        time.sleep(0.05)
    p.wait()
    ready, _, _ = select.select([p.stdout], [], [], 0)
    out = p.stdout.read() if ready else ""
    p.stdout.close()
    errfile.seek(0)
    return out, errfile.read(), timed_out, again


def failed_run_stderr(err):
    """A failed run's whole stderr (servo-bus's and its servos', which share
    it), indented: the reason a servo died is rarely its last line."""
    lines = err.rstrip().splitlines() or ["(nothing on stderr)"]
    return "\n".join("    | " + ln for ln in lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--backend", default="host-sim", choices=("host-sim", "qemu"))
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--seed", type=int, default=None)
    ap.add_argument("--signal", default="INT", choices=("INT", "TERM"))
    ap.add_argument("--ids", default="1,2,3")
    ap.add_argument("--demo", action="store_true",
                    help="interrupt tools/servo-demo (build, bus, kmx session) instead")
    a = ap.parse_args()
    if ctypes.CDLL(None, use_errno=True).prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) != 0:
        print("cannot become a child subreaper: errno %d" % ctypes.get_errno())
        return 2
    seed = a.seed if a.seed is not None else int(time.time())
    rng = random.Random(seed)
    sig = getattr(signal, "SIG" + a.signal)
    argv = [sys.executable, os.path.join(REPO, "sim", "bus", "servo-bus"), "--ids", a.ids, "--port", "0",
            "--backend", a.backend]
    ready_text = "ready "
    if a.demo:
        argv = [os.path.join(REPO, "tools", "servo-demo"), "--backend", a.backend]
        ready_text = "== bus ready"

    errfile = tempfile.TemporaryFile(mode="w+")
    t0 = time.monotonic()
    p = start(argv, errfile)
    line = ""
    while not line.startswith(ready_text):
        ready, _, _ = select.select([p.stdout], [], [], 120)
        line = p.stdout.readline() if ready else ""
        if not line:
            break
    ready_s = time.monotonic() - t0
    os.killpg(p.pid, sig)
    out, err, _, _ = finish(p, errfile, sig)
    if not line.startswith(ready_text):
        print("servo-bus did not start: %r\n%s" % (line, err))
        return 2
    print("# %s: ready after %.2f s untouched; seed %d, SIG%s" % (a.backend, ready_s, seed, a.signal), flush=True)

    bad = 0
    early = 0
    dropped = 0
    races = 0
    handlers_at = handlers_line()
    t_all = time.monotonic()
    for n in range(1, a.runs + 1):
        delay = rng.uniform(0.0, 1.3 * ready_s)
        p = start(argv, errfile)
        started = time.monotonic()
        time.sleep(delay)
        ready_before = ready_written(p)
        sent = time.monotonic() - started  # a loaded host oversleeps
        os.killpg(p.pid, sig)
        out, err, timed_out, again = finish(p, errfile, sig)
        if timed_out:
            err += "\n(servo-bus did not exit within 30 s of the signal)"
        time.sleep(0.2)  # a killed child's re-parenting is not instant
        left = children()
        problems = []
        if left:
            problems.append("left %s" % ", ".join("pid %d (%s)" % (pid, command_of(pid)[:60]) for pid in left))
            for pid in left:
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
        if again:  # Python's report of the signal it dropped is no failure of servo-bus's
            err = err[err.index("\n", err.index("KeyboardInterrupt")) + 1:]
        where = [ln.strip() for ln in err.splitlines() if ln.strip().startswith("File ")]
        # Python's own start-up, before servo-bus's first line (its signal
        # handlers) runs: the default SIGINT action, or KeyboardInterrupt
        # while the interpreter initialises, imports site or compiles the
        # script (printed with a traceback, in a "Fatal Python error", or
        # alone: exit 1 with "KeyboardInterrupt" only, 2 in 200 early runs;
        # or exit 1 with PYTHON_NO_LOADER alone, once in 900 runs).
        # Nothing is started then; counted apart, not a failure.
        if a.demo and p.returncode in (0, 130, -sig):
            p.returncode = 0  # the demo's own goodbye, or killed before its trap
        interrupted = err.strip().endswith("KeyboardInterrupt")
        in_python_startup = not a.demo and not left and (
            (p.returncode == -sig and not err.strip()) or
            (interrupted and not after_handlers(where, handlers_at)) or
            (p.returncode == 1 and err.strip() == PYTHON_NO_LOADER))
        if not in_python_startup:
            if p.returncode != 0:
                last = err.strip().splitlines()[-1:] or ["(nothing on stderr)"]
                problems.append("exit status %d, stderr ends: %s" % (p.returncode, last[0][:200]))
            if "Traceback" in err:
                problems.append("traceback: %s at %s" % (err.strip().splitlines()[-1],
                                                         where[-1] if where else "?"))
        # ready written after the signal was sent: it came after servo-bus's
        # final check, in the microseconds before the line went out (its
        # announce_ready); then the bus must stop at once, as after ready
        raced = ready_text in out and not ready_before
        stage = ("Python dropped it in its start-up, sent again" if again else
                 "ready raced the signal" if raced else "after ready" if ready_text in out else
                 "in Python's start-up, nothing started" if in_python_startup else "during start-up")
        early += in_python_startup
        dropped += again
        races += raced
        print("run %2d: SIG%s at %.3f s, drawn %.3f (%s): %s"
              % (n, a.signal, sent, delay, stage, "; ".join(problems) if problems else "clean"), flush=True)
        if problems:
            print(failed_run_stderr(err), flush=True)
        bad += bool(problems)
        children()  # reap
    print("%d runs, %d left processes behind or failed (%d interrupted Python's own start-up, "
          "%d dropped by it and sent again, %d ready lines raced the signal; %s, %.0f s)"
          % (a.runs, bad, early, dropped, races, a.backend, time.monotonic() - t_all))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
