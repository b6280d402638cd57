# SPDX-License-Identifier: Apache-2.0
"""The check registry and the master-side helpers every check uses.

A check is a function ctx -> None registered with @check(name, basis, doc):
it raises Fail(why) or Skip(why), or returns (PASS). basis is the
docs/protocol.md section it tests, or "decision: <heading>" when the spec is open
and docs/protocol-decisions.md settles it (the name then starts with
"decision:"). Helpers talk frames through wire.py and never assume the
servo's answers: every expectation is the caller's, from the spec.
"""
import time

import spec
from wire import fr

CHECKS = []


class Fail(Exception):
    pass


class Skip(Exception):
    pass


class Check:
    def __init__(self, name, basis, doc, fn):
        self.name, self.basis, self.doc, self.fn = name, basis, doc, fn


def check(name, basis, doc=""):
    if name.startswith("decision:") != basis.startswith("decision"):
        raise ValueError("%s: a check on a decision is named decision:..." % name)

    def wrap(fn):
        CHECKS.append(Check(name, basis, doc or (fn.__doc__ or "").strip(), fn))
        return fn
    return wrap


def expect(cond, why):
    if not cond:
        raise Fail(why)


def hexs(b):
    return bytes(b).hex(" ")


class Ctx:
    """One bus, the servos under test, and the timing the master uses."""

    def __init__(self, wire, ids, opts):
        self.wire = wire
        self.ids = ids
        self.opts = opts
        self.timeout = opts.timeout          # s for an answer that is due
        self.quiet = opts.quiet_ms / 1000.0  # s of silence that means "no answer"
        self.level = {}                      # response level (0x11 bit 3) per servo
        self.log = opts.log

    # ---- raw ------------------------------------------------------------
    def send(self, frame):
        self.wire.send(frame)

    def ask(self, frame, expect_n=1, timeout=None):
        r = self.wire.transact(frame, expect_n, timeout or self.timeout)
        self.log("> %s < %s" % (hexs(frame), " | ".join(hexs(f.to_bytes()) for f in r)))
        return r

    def silent(self, frame, why="no answer"):
        """Sends frame; fails when anything answers within the quiet window."""
        got = self.wire.transact(frame, None, self.quiet + 0.05, quiet=self.quiet)
        expect(not got, "%s expected to %s, got %s" % (
            why, hexs(frame), " | ".join(hexs(f.to_bytes()) for f in got)))

    def no_answer(self, frame):
        return self.wire.transact(frame, None, self.quiet + 0.05, quiet=self.quiet)

    # ---- ping / status -------------------------------------------------
    def ping(self, dev_id, timeout=None):
        """The short response's status byte, or None when nobody answered."""
        r = self.ask(fr.ping(dev_id), 1, timeout)
        if not r:
            return None
        f = r[0]
        expect(f.id == dev_id and f.is_status,
               "ping %d answered by %r, expected a short response from %d" % (dev_id, f, dev_id))
        return f.status

    def status(self, dev_id):
        s = self.ping(dev_id)
        expect(s is not None, "servo %d does not answer a ping" % dev_id)
        return s

    def clean(self, dev_id):
        """Pings until bits 5/6 are clear (any unreported outcome is reported)."""
        for _ in range(3):
            if not self.status(dev_id) & spec.BITS_56:
                return
        raise Fail("servo %d: status bits 5/6 stay set over three pings" % dev_id)

    # ---- read ----------------------------------------------------------
    def read_frame(self, dev_id, addr):
        r = self.ask(fr.read(dev_id, addr))
        expect(r, "read 0x%02X of servo %d: no answer" % (addr, dev_id))
        return r[0]

    def read(self, dev_id, addr):
        """The value bytes of a read answer; fails on anything else."""
        f = self.read_frame(dev_id, addr)
        expect(f.id == dev_id and not f.is_status and f.cmd == fr.READ and f.addr == addr,
               "read 0x%02X of servo %d answered %s (expected F9 F5 %02X len 02 %02X ...)"
               % (addr, dev_id, hexs(f.to_bytes()), dev_id, addr))
        return f.params

    def read_int(self, dev_id, addr, signed=None):
        reg = spec.BY_ADDR.get(addr)
        if signed is None:
            signed = bool(reg and reg.signed)
        return spec.to_int(self.read(dev_id, addr), signed)

    def read_fields(self, dev_id, addr):
        raw = self.read(dev_id, addr)
        out, at = [], 0
        for n in spec.BY_ADDR[addr].fields:
            out.append(spec.to_int(raw[at:at + n]))
            at += n
        return tuple(out)

    # ---- write ---------------------------------------------------------
    def response_level(self, dev_id):
        if dev_id not in self.level:
            self.level[dev_id] = (self.read_int(dev_id, 0x11) >> 3) & 1
        return self.level[dev_id]

    def write(self, dev_id, addr, value):
        """Writes and returns the status bits that report this write: the
        write's own short response at response level 1, else the next ping's
        (§4: bits 5/6 are reported by the next command's answer)."""
        frame = fr.write(dev_id, addr, value)
        if addr in (0x03, 0x11):
            # A write that changes the response level is answered at the
            # level in force after it (decision: "Response level of a write").
            r = self.no_answer(frame)
            expect(len(r) <= 1 and all(f.id == dev_id and f.is_status for f in r),
                   "write 0x%02X to servo %d answered %s" % (addr, dev_id, [hexs(f.to_bytes()) for f in r]))
            st = r[0].status if r else self.status(dev_id)
        elif self.response_level(dev_id):
            r = self.ask(frame)
            expect(r and r[0].id == dev_id and r[0].is_status,
                   "write 0x%02X to servo %d at response level 1: answered %s, expected a short "
                   "response (§3)" % (addr, dev_id, [hexs(f.to_bytes()) for f in r]))
            st = r[0].status
        else:
            self.send(frame)
            st = None
            if addr == 0x0F and len(value) == 1 and value[0] != dev_id and value[0] <= spec.ID_MAX:
                st = self.ping(value[0], timeout=0.15)  # §3: the new ID applies at once
                if st is not None:
                    self.level.pop(value[0], None)
            if st is None:
                st = self.status(dev_id)
        if addr == 0x03:
            self.level.pop(dev_id, None)
        if addr == 0x11 and not st & spec.BITS_56:
            self.level[dev_id] = (value[0] >> 3) & 1
        return st

    def write_ok(self, dev_id, addr, value, what=""):
        st = self.write(dev_id, addr, value)
        expect(not st & spec.BITS_56, "%swrite 0x%02X = %s to servo %d: status 0x%02X, expected "
               "bits 5/6 clear" % (what, addr, hexs(value), dev_id, st))

    def write_fails(self, dev_id, addr, value, bit, what=""):
        st = self.write(dev_id, addr, value)
        expect(st & spec.BITS_56 == bit, "%swrite 0x%02X = %s to servo %d: status 0x%02X, expected "
               "bit %d alone of bits 5/6" % (what, addr, hexs(value), dev_id, st,
                                            6 if bit == spec.BIT_FAILED else 5))
        self.clean(dev_id)

    # ---- restart -------------------------------------------------------
    def restart(self, dev_id, answer_id=None, seconds=None, wait=True):
        """§3: write 0x02 E1 E2 E3 E4, no answer; then (wait) waits for a
        ping on answer_id (default dev_id)."""
        answer_id = dev_id if answer_id is None else answer_id
        got = self.no_answer(fr.write(dev_id, 0x02, spec.RESTART_MAGIC))
        expect(not got, "restart of servo %d answered %s (§3: no answer)" % (
            dev_id, [hexs(f.to_bytes()) for f in got]))
        self.level.pop(dev_id, None)
        self.level.pop(answer_id, None)
        if wait:
            expect(self.wait_ping(answer_id, seconds), "servo %d does not answer after a restart"
                   % answer_id)

    def wait_ping(self, dev_id, seconds=None):
        end = time.monotonic() + (seconds or self.opts.restart_s) * getattr(self.opts, "time_scale", 1.0)
        while time.monotonic() < end:
            if self.ping(dev_id, timeout=0.2) is not None:
                return True
        return False

    # ---- saved settings ------------------------------------------------
    def snapshot(self, dev_id, addrs):
        return {a: self.read(dev_id, a) for a in addrs}

    def restore(self, dev_id, saved):
        """Writes saved values back (limits in the order that keeps them
        consistent: 0x13..0x15 before 0x5B..0x5D, angle limits via 0)."""
        order = sorted(saved, key=lambda a: (a in spec.FOLLOWS, a))
        if 0x19 in saved and 0x1A in saved:
            self.write(dev_id, 0x19, spec.i16(0))
            self.write(dev_id, 0x1A, spec.i16(0))
        for a in order:
            if self.read(dev_id, a) != saved[a]:
                self.write_ok(dev_id, a, saved[a], "restore: ")

    def other_id(self, avoid=()):
        """An ID in 1..250 nobody on the bus answers (for ID changes)."""
        for cand in range(200, 0, -1):
            if cand in self.ids or cand in avoid:
                continue
            if self.ping(cand, timeout=min(self.timeout, 0.15)) is None:
                return cand
        raise Skip("no free ID found on the bus")
