# SPDX-License-Identifier: Apache-2.0
"""servo-bus with virtual STM32G031 servos for a test's master: started on a
free TCP port, its virtual clock installed in the master's process, stopped
at the end (tests/g031/update_on_bus.py, tests/footprint/f6_monitor.py)."""
import contextlib
import os
import signal
import subprocess

import vclock

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))


@contextlib.contextmanager
def servo_bus(ids, args, tmpdir, env=None):
    """sim/bus/servo-bus --backend g031 with servos `ids` and servo-bus
    options `args`, its clock file in tmpdir and installed here (the
    master's waits in the servos' virtual time): yields (spec, clock);
    raises RuntimeError when servo-bus does not start."""
    clock_file = os.path.join(tmpdir, "clock")
    proc = subprocess.Popen([os.path.join(REPO, "sim", "bus", "servo-bus"), "--backend", "g031", "--ids",
                             ",".join(map(str, ids)), "--port", "0", "--clock-file", clock_file, *args],
                            stdout=subprocess.PIPE, text=True, env=env)
    try:
        line = proc.stdout.readline().strip()
        if not line.startswith("ready "):
            raise RuntimeError("servo-bus did not start: %r" % line)
        yield "tcp:" + line.split()[1], vclock.install(clock_file)
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        proc.stdout.close()
