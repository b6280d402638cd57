# SPDX-License-Identifier: Apache-2.0
"""The simulated boards' builds and sim/bus/servo-bus as a child process.

Which build tree holds the image servo-bus runs for a backend comes from
board discovery, as for the rest of the build (cmake/km_boards.cmake): the
board whose board.cmake names that KM_BOARD_BUS_BACKEND, its image
KM_BOARD_BUS_IMAGE, in the binaryDir of the configure preset that builds it
(CMakePresets.json). KM_BUILD_DIR_<board> in the environment (the board's
name with '-' as '_', e.g. KM_BUILD_DIR_qemu_microbit; CTest sets it from
the cache variable of that name) points at another build tree.

    with ServoBusProcess(["--ids", "1,2,3", "--backend", "host-sim"]) as bus:
        ... bus.spec (tcp:127.0.0.1:PORT), bus.port ...
"""
import collections
import functools
import os
import shutil
import signal
import subprocess
import sys

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
SERVO_BUS = os.path.join(REPO, "sim", "bus", "servo-bus")
KM_BOARDS = os.path.join(REPO, "cmake", "km_boards.cmake")

Board = collections.namedtuple("Board", "name build_dir preset image")


class BuildMissing(Exception):
    """No board or no build for a backend; the message says what to run."""


STOP_SIGNALS = {signal.SIGINT, signal.SIGTERM}


def run_unsignalled(argv):
    """subprocess.run(argv) that a Ctrl-C or SIGTERM to the caller's process
    group never kills: its own session, and SIGINT and SIGTERM blocked in it.
    A session alone leaves a window: the child is in the caller's group from
    fork to setsid (docs/architecture.md "servo-bus's start-up: ports and
    signals"). The blocked mask is inherited across exec, so a signal caught
    in that window stays pending, never delivered. The caller's own mask is restored at once: it
    sees the signal itself (servo-bus then stops at its next check)."""
    old = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    try:
        proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                start_new_session=True)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
    out, err = proc.communicate()
    return subprocess.CompletedProcess(argv, proc.returncode, out, err)


@functools.lru_cache(maxsize=None)
def bus_boards():
    """{backend: Board} for every board that names a bus backend (cmake/km_boards.cmake)."""
    cmake = shutil.which("cmake")
    if not cmake:
        raise BuildMissing("cmake is not on PATH: it finds the boards (cmake/km_boards.cmake)")
    r = run_unsignalled([cmake, "-DKM_BOARDS_QUERY=bus", "-P", KM_BOARDS])
    if r.returncode != 0:
        raise BuildMissing("board discovery failed (cmake -DKM_BOARDS_QUERY=bus -P %s): %s"
                           % (KM_BOARDS, r.stderr.strip() or "exit status %d" % r.returncode))
    boards = {}
    for line in r.stdout.splitlines():
        words = line.split()
        if len(words) == 5:
            boards[words[0]] = Board(*words[1:])
    return boards


def board_for(backend):
    """The Board that servo-bus's `backend` runs; BuildMissing when no board names it."""
    boards = bus_boards()
    if backend not in boards:
        raise BuildMissing("no board names the bus backend %r (KM_BOARD_BUS_BACKEND in boards/*/board.cmake; "
                           "named: %s)" % (backend, ", ".join(sorted(boards)) or "none"))
    return boards[backend]


def build_env_name(board_name):
    """The environment variable that points at another build tree of a board."""
    return "KM_BUILD_DIR_" + board_name.replace("-", "_")


def build_dir(backend, override=None):
    """The build tree of `backend`'s board: `override`, else $KM_BUILD_DIR_<board>, else its preset's."""
    board = board_for(backend)
    chosen = override or os.environ.get(build_env_name(board.name)) or board.build_dir
    return os.path.join(REPO, chosen)


def build_hint(backend, tree=None):
    """The commands that build `backend`'s board (into `tree` when it is not the preset's)."""
    board = board_for(backend)
    if board.preset != "-" and (tree is None or os.path.abspath(tree) == os.path.abspath(board.build_dir)):
        return "cmake --preset %s && cmake --build --preset %s" % (board.preset, board.preset)
    tree = tree or board.build_dir
    return "cmake -S %s -B %s -DKM_BOARD=%s && cmake --build %s" % (REPO, tree, board.name, tree)


def default_image(backend, override=None):
    """(the servo image servo-bus runs for `backend`, the commands that build it)."""
    tree = build_dir(backend, override)
    return os.path.join(tree, board_for(backend).image), build_hint(backend, tree)


class NotReady(Exception):
    """servo-bus exited or printed something else before its `ready` line."""


class ServoBusProcess:
    """sim/bus/servo-bus on a free port (--port 0), stopped on close (SIGTERM, then SIGKILL)."""

    def __init__(self, args, python=None, stderr=None):
        argv = [python or sys.executable, SERVO_BUS, "--port", "0"] + [str(a) for a in args]
        # Same process group as the caller: a CTest timeout that kills the
        # group takes the bus and its servos with it.
        self.proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=stderr, text=True)
        try:
            self.ready_line = self.proc.stdout.readline().strip()
        except BaseException:  # a signal while it starts: stop it all the same
            self.close()
            raise
        if not self.ready_line.startswith("ready "):
            self.close()
            raise NotReady("servo-bus did not get ready (exit %s): %r" % (self.proc.returncode, self.ready_line))
        self.address = self.ready_line.split()[1]
        self.host, port = self.address.rsplit(":", 1)
        self.port = int(port)
        self.spec = "tcp:" + self.address

    def close(self):
        """Stops the bus and its servos; returns servo-bus's exit status."""
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return self.proc.returncode

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
