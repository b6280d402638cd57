# SPDX-License-Identifier: Apache-2.0
"""Request and answers on one bus, for the conformance suite, on host/kmx.

Frames and transports are kmx's (kmx.frame, kmx.transport.open_transport);
this file adds what a conformance master needs beyond kmx.Bus:
  - answers are collected until a count or a quiet window, and nothing is
    hidden: frames that arrive before a request are late answers to an
    earlier one (kept in Wire.stale, a failure), echoes of our own frames
    on a half-duplex wire are dropped, bad frames are counted;
  - tcp:HOST:PORT@BAUD keeps the master to that line rate on an emulated
    bus (Paced below), which TCP alone does not; rfc2217:HOST:PORT@BAUD
    (sim/bus/servo-bus as a serial port) also sets the master's baud on the
    emulated wire, and set_baud() changes it, as on a serial bus.
"""
import time

from kmx import frame as fr  # noqa: E402
from kmx import transport as kt  # noqa: E402


class Paced:
    """A TCP transport that keeps to a line rate: it never sends while the
    half-duplex wire would still carry earlier bytes, its own or an answer
    (an emulated servo may hand its answer to TCP whole at its first byte).
    Without it the master outruns the emulated wire, and servos that pace
    what they hear (host-sim) fall behind by more at every exchange."""

    def __init__(self, inner, baud):
        self.inner = inner
        self.byte_s = 10.0 / baud
        self.free_at = 0.0  # monotonic time the wire is free

    def set_baud(self, baud):
        self.inner.set_baud(baud)
        self.byte_s = 10.0 / baud

    def _busy(self, n):
        self.free_at = max(self.free_at, time.monotonic()) + n * self.byte_s

    def write(self, data):
        wait = self.free_at - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        self._busy(len(data))
        self.inner.write(data)

    def read(self, timeout):
        data = self.inner.read(timeout)
        if data:
            self._busy(len(data))
        return data

    def close(self):
        self.inner.close()


def open_bus(spec):
    """(transport, kind, can_set_baud) for tcp:HOST:PORT[@BAUD],
    rfc2217:HOST:PORT[@BAUD], serial:DEV[@BAUD] or pty:/dev/pts/N."""
    if spec.startswith("tcp:") and "@" in spec:
        base, _, baud = spec.partition("@")
        kt.parse_spec(base)
        if not baud.isdigit() or int(baud) <= 0:
            raise SystemExit("--bus %s: the baud after @ must be a positive number" % spec)
        return Paced(kt.open_transport(base), int(baud)), "tcp", False
    kind, p = kt.parse_spec(spec)
    if kind == "rfc2217":
        return Paced(kt.open_transport(spec), p["baud"]), kind, True
    # A pty has no line rate: a baud set on it changes nothing on the wire.
    return kt.open_transport(spec), kind, kind == "serial"


class Wire:
    def __init__(self, spec, time_scale=1.0):
        self.t, self.kind, self.can_set_baud = open_bus(spec)
        self.time_scale = time_scale  # every wait for answers or quiet, multiplied (--time-scale)
        self.parser = fr.Parser(headers=(fr.RSP_HEADER, fr.CMD_HEADER))
        self.stale = []    # frames that arrived before the request they were read for
        self.sent = set()  # our own frames (their echo is no answer)

    @property
    def bad_frames(self):
        return self.parser.bad_frames

    def _frames(self, data):
        out = []
        for f in self.parser.feed(data):
            if f.to_bytes() in self.sent:
                continue  # our own frame heard back
            if f.is_command:
                raise ConnectionError("a command frame we did not send: another master? %r" % f)
            out.append(f)
        return out

    def send(self, data):
        data = bytes(data)
        while True:  # whatever waits now answered something earlier
            got = self.t.read(0)
            if not got:
                break
            self.stale += self._frames(got)
        self.sent = {data}
        self.t.write(data)

    def collect(self, expect, timeout, quiet=None):
        """Answer frames until `expect` of them came (expect=None: until
        `quiet` seconds pass without a byte) or `timeout` seconds passed."""
        got = []
        timeout *= self.time_scale
        quiet = None if quiet is None else quiet * self.time_scale
        end = time.monotonic() + timeout
        while expect is None or len(got) < expect:
            left = end - time.monotonic()
            if left <= 0:
                break
            data = self.t.read(left if quiet is None else min(left, quiet))
            if data:
                got += self._frames(data)
            elif quiet is not None:
                break
        return got

    def transact(self, frame, expect=1, timeout=0.5, quiet=None):
        self.send(frame)
        return self.collect(expect, timeout, quiet)

    def drain(self, quiet):
        """Everything that arrives until the bus is quiet for `quiet` s."""
        return self.collect(None, 10.0, quiet)

    def set_baud(self, baud):
        self.t.set_baud(baud)  # kmx's SerialTransport, or Paced over RFC 2217

    def close(self):
        self.t.close()
