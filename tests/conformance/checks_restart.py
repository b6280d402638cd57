# SPDX-License-Identifier: Apache-2.0
"""§3/§5.1 across a restart (write 0x02 E1 E2 E3 E4): ID change, baud
change, persistence of user data (P) and the live registers' defaults, the
user-data resets of 0x03 (levels 1 and 2) and the defaults they restore."""
import statistics
import time

import spec
from ctx import Fail, Skip, check, expect, hexs
from wire import fr

LIVE = [0x5A, 0x5B, 0x5C, 0x5D, 0x64]
SETTINGS = [a for a in spec.PERSISTED_RW if a not in (0x0F, 0x10)] + LIVE


def _settings(ctx, i):
    return ctx.snapshot(i, SETTINGS)


@check("restart.no-answer", "§3 restart, §5.1 0x02",
       "0x02 E1 E2 E3 E4 is never answered (also at response level 1); the servo answers again")
def restart_basic(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x11])
    try:
        ctx.write_ok(i, 0x11, bytes([saved[0x11][0] | 0x08]))
        ctx.restart(i)
    finally:
        ctx.restore(i, saved)


@check("restart.bad-magic", "§3 restart (exactly E1 E2 E3 E4), §4 bit 6",
       "0x02 with other bytes or another length: bit 6, no restart (0x5A survives)")
def restart_bad(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x5A])
    try:
        ctx.write_ok(i, 0x5A, b"\x01")
        for v in (b"\xE1\xE2\xE3\xE5", b"\xE1\xE2\xE3", b"\xE1\xE2\xE3\xE4\x00"):
            ctx.write_fails(i, 0x02, v, spec.BIT_FAILED)
        expect(ctx.read_int(i, 0x5A) == 1, "0x5A back at its default: the servo restarted")
    finally:
        ctx.restore(i, saved)


@check("restart.persistence", "§5 (P = kept across power-off / restart), §5.4 defaults",
       "persisted registers keep written values across a restart; live ones return to "
       "their defaults (0x5A 0, 0x64 3, 0x5B = 0x13)")
def restart_persist(ctx):
    i = ctx.ids[0]
    saved = _settings(ctx, i)
    try:
        ctx.restore(i, {0x19: spec.i16(0), 0x1A: spec.i16(0)})
        values = {0x12: spec.u16(321), 0x13: spec.u16(876), 0x32: spec.u8(0x0B), 0x33: spec.u8(0x05),
                  0x34: spec.u8(0x55), 0x3D: bytes([65, 7]), 0x3F: spec.u16(700) + spec.u8(15),
                  0x17: spec.i16(12), 0x19: spec.i16(-300), 0x1A: spec.i16(300)}
        for a, v in values.items():
            ctx.write_ok(i, a, v)
        ctx.write_ok(i, 0x5A, b"\x01")
        ctx.write_ok(i, 0x5B, spec.u16(500))
        ctx.write_ok(i, 0x64, b"\x00")
        ctx.restart(i)
        for a, v in values.items():
            got = ctx.read(i, a)
            expect(got == v, "0x%02X = %s after the restart, written %s" % (a, hexs(got), hexs(v)))
        expect(ctx.read_int(i, 0x5A) == 0, "0x5A = %d after restart (default 0)" % ctx.read_int(i, 0x5A))
        expect(ctx.read_int(i, 0x64) == 3, "0x64 = %d after restart (default 3)" % ctx.read_int(i, 0x64))
        for live, mx in spec.FOLLOWS.items():
            expect(ctx.read(i, live) == ctx.read(i, mx), "0x%02X = %s, 0x%02X = %s after restart"
                   % (live, hexs(ctx.read(i, live)), mx, hexs(ctx.read(i, mx))))
    finally:
        ctx.restore(i, saved)


@check("restart.id-change", "§3 ID change, §5.1 0x0F (0..250, P)",
       "0x0F = 250 (or a free ID): answered with the old ID at level 1, the new ID at once, "
       "kept across a restart; then back")
def restart_id(ctx):
    i = ctx.ids[-1]
    new = 250 if 250 not in ctx.ids and ctx.ping(250, timeout=0.15) is None else ctx.other_id()
    saved = ctx.snapshot(i, [0x11])
    moved = False
    try:
        ctx.write_ok(i, 0x11, bytes([saved[0x11][0] | 0x08]))
        r = ctx.ask(fr.write(i, 0x0F, spec.u8(new)))
        moved = True
        expect(len(r) == 1 and r[0].id == i and r[0].is_status and not r[0].status & spec.BITS_56,
               "0x0F write answered %s, expected a short response from the old ID %d"
               % ([hexs(f.to_bytes()) for f in r], i))
        expect(ctx.ping(new) is not None, "no answer on the new ID %d" % new)
        expect(ctx.ping(i, timeout=0.15) is None, "still answers on the old ID %d" % i)
        ctx.restart(new)
        expect(ctx.ping(i, timeout=0.15) is None, "answers on the old ID %d after restart" % i)
        expect(ctx.read_int(new, 0x0F) == new, "0x0F reads %d" % ctx.read_int(new, 0x0F))
        ctx.level.pop(new, None)
        ctx.write_ok(new, 0x0F, spec.u8(i))
        moved = False
        ctx.restart(i)
        expect(ctx.read_int(i, 0x0F) == i, "0x0F reads %d after moving back" % ctx.read_int(i, 0x0F))
    finally:
        if moved and ctx.ping(new, timeout=0.2) is not None:
            ctx.send(fr.write(new, 0x0F, spec.u8(i)))
            ctx.wait_ping(i, 2)
        ctx.level.pop(i, None)
        ctx.restore(i, saved)


def _rtt(ctx, i, n=15):
    ts = []
    for _ in range(n):
        t = time.perf_counter()
        expect(ctx.ping(i) is not None, "servo %d stopped answering" % i)
        ts.append(time.perf_counter() - t)
    return statistics.median(ts)


def _baud_cycle(ctx, observe):
    """Writes 0x10 = another baud, restarts, calls observe(i, old, new, rtt
    at the old rate), and always goes back to the old baud."""
    i = ctx.ids[0]
    old = ctx.read_int(i, 0x10)
    new = 96 if old >= 192 else 1152  # 9600, or 115200 from a slow bus
    serial = ctx.transport.can_set_baud
    rtt_old = _rtt(ctx, i)
    ctx.write_ok(i, 0x10, spec.u16(new))
    expect(ctx.read_int(i, 0x10) == new, "0x10 not stored")
    switched = False
    try:
        ctx.restart(i, wait=not serial)
        if serial:
            ctx.wire.set_baud(new * 100)
            switched = True
            expect(ctx.wait_ping(i), "no answer at %d baud after the restart" % (new * 100))
        return observe(i, old, new, rtt_old)
    finally:
        ctx.write(i, 0x10, spec.u16(old))
        ctx.send(fr.write(i, 0x02, spec.RESTART_MAGIC))
        if switched:
            time.sleep(0.05)
            ctx.wire.set_baud(old * 100)
        if not ctx.wait_ping(i):
            raise Fail("servo %d lost: no answer after restoring baud %d" % (i, old * 100))
        ctx.level.pop(i, None)
        expect(ctx.read_int(i, 0x10) == old, "0x10 not restored")


@check("baud.stored-across-restart", "§3 baud change, §5.1 0x10 (P, effective after restart)",
       "0x10 written reads back at once, and again after a restart; then restored")
def baud_stored(ctx):
    def observe(i, old, new, rtt):
        expect(ctx.read_int(i, 0x10) == new, "0x10 = %d after the restart, written %d"
               % (ctx.read_int(i, 0x10), new))
    _baud_cycle(ctx, observe)


@check("baud.line-rate-after-restart", "§3 baud change (takes effect after restart)",
       "after 0x10 and a restart the servo talks at the new baud and no longer at the old: on a "
       "serial or RFC 2217 bus the master switches and pings at both (an answer at the old "
       "rate too: SKIP, the emulated wire does not model the line rate, as on QEMU); on TCP "
       "the ping round trip must grow by the byte-time difference, else SKIP")
def baud_line_rate(ctx):
    if ctx.transport.kind == "pty":
        raise Skip("a pseudo-terminal has no line rate; run on a serial bus")

    def observe(i, old, new, rtt_old):
        if ctx.transport.can_set_baud:
            # answered at the new rate after switching; the old must be garbage now
            ctx.wire.set_baud(old * 100)
            time.sleep(0.02)
            ctx.wire.drain(0.05)
            heard = ctx.ping(i) is not None
            ctx.wire.set_baud(new * 100)
            time.sleep(0.02)
            ctx.wire.drain(0.05)
            if heard:
                raise Skip("line rate not modelled on this bus: after the restart servo %d answers "
                           "at %d and at %d baud (QEMU's UART has no line rate); 0x10 stored "
                           "across restart: baud.stored-across-restart" % (i, new * 100, old * 100))
            ctx.log("servo %d answers at %d baud and not at %d after the restart" % (i, new * 100, old * 100))
            return
        rtt_new = _rtt(ctx, i)
        # The ping's own 6 bytes: a servo at the new rate cannot have the
        # request (and answer it) before they are in, whatever its TX does.
        want = 6 * 10 * (1.0 / (new * 100) - 1.0 / (old * 100))
        ctx.log("ping round trip %.2f ms at %d, %.2f ms at %d (byte times differ by %.2f ms)"
                % (rtt_old * 1e3, old * 100, rtt_new * 1e3, new * 100, want * 1e3))
        if abs(rtt_new - rtt_old) < abs(want) / 2:
            raise Skip("line rate not modelled on this %s bus: the ping round trip stayed "
                       "%.2f -> %.2f ms at %d -> %d baud (the request's bytes alone change it by %.1f ms); "
                       "0x10 stored across restart: baud.stored-across-restart"
                       % (ctx.transport.kind, rtt_old * 1e3, rtt_new * 1e3, old * 100,
                          new * 100, want * 1e3))
        expect((rtt_new - rtt_old) * want > 0, "round trip moved the wrong way")
    _baud_cycle(ctx, observe)


def _defaults_ok(ctx, i, skip=()):
    bad = []
    for r in spec.REGISTERS:
        if r.default is None or not r.persisted or r.addr in skip:
            continue
        if r.fields:
            got = ctx.read_fields(i, r.addr)
            want = r.default if isinstance(r.default, tuple) else (r.default,)
            if any(w is not None and g != w for g, w in zip(got, want)):
                bad.append("0x%02X = %s (default %s)" % (r.addr, got, want))
        else:
            got = ctx.read_int(i, r.addr)
            if got != r.default:
                bad.append("0x%02X = %d (default %d)" % (r.addr, got, r.default))
    for live, mx in spec.FOLLOWS.items():
        if ctx.read(i, live) != ctx.read(i, mx):
            bad.append("0x%02X != 0x%02X" % (live, mx))
    expect(not bad, "; ".join(bad))


def _changed_settings(ctx, i):
    ctx.restore(i, {0x19: spec.i16(0), 0x1A: spec.i16(0)})
    for a, v in ((0x12, spec.u16(333)), (0x13, spec.u16(900)), (0x32, spec.u8(0x07)),
                 (0x33, spec.u8(0x01)), (0x34, spec.u8(0x55)), (0x3D, bytes([70, 10])),
                 (0x3F, spec.u16(500) + spec.u8(10)), (0x17, spec.i16(10))):
        ctx.write_ok(i, a, v)


def _reset(ctx, i, level):
    """0x03 = level: answered or not (the answer follows 0x11 after the
    reset, a decision); then a clean ping on the ID in force."""
    got = ctx.no_answer(fr.write(i, 0x03, spec.u8(level)))
    expect(all(f.is_status and not f.status & spec.BITS_56 for f in got),
           "0x03 = %d answered %s" % (level, [hexs(f.to_bytes()) for f in got]))
    ctx.level.pop(i, None)


@check("reset.level1", "§5.1 0x03 level 1, §5.1/§5.2 defaults",
       "0x03 = 1 resets user data to the spec's defaults except ID, baud and zero offsets")
def reset_level1(ctx):
    i = ctx.ids[0]
    saved = _settings(ctx, i)
    keep = ctx.snapshot(i, [0x0F, 0x10, 0x16])
    try:
        _changed_settings(ctx, i)
        _reset(ctx, i, 1)
        expect(not ctx.status(i) & spec.BITS_56, "status bits after the reset")
        _defaults_ok(ctx, i, skip=spec.KEPT_BY_LEVEL1)
        expect(ctx.read_int(i, 0x17) == 10, "0x17 (a zero offset) not kept: %d" % ctx.read_int(i, 0x17))
        for a, v in keep.items():
            expect(ctx.read(i, a) == v, "0x%02X not kept" % a)
    finally:
        ctx.restore(i, saved)


@check("reset.level2", "§5.1 0x03 level 2, 0x0F default 0, 0x10 default 1152",
       "0x03 = 2 resets all user data: ID 0 (answering on ID 0), baud 1152, 0x17 0; then restored")
def reset_level2(ctx):
    i = ctx.ids[-1]
    if i != 0 and ctx.ping(0, timeout=0.15) is not None:
        raise Skip("another servo answers on ID 0, the ID a level-2 reset gives")
    saved = _settings(ctx, i)
    baud = ctx.read(i, 0x10)
    on = i
    try:
        _changed_settings(ctx, i)
        _reset(ctx, i, 2)
        on = 0
        expect(ctx.ping(0) is not None, "no answer on ID 0 after the level-2 reset")
        if i != 0:
            expect(ctx.ping(i, timeout=0.15) is None, "still answers on ID %d" % i)
        _defaults_ok(ctx, 0)
    finally:
        if on == 0 and ctx.ping(0, timeout=0.3) is not None:
            ctx.level.pop(0, None)
            ctx.write_ok(0, 0x10, baud)
            if i != 0:
                ctx.write_ok(0, 0x0F, spec.u8(i))
        ctx.level.pop(i, None)
        ctx.restore(i, saved)


@check("decision:reset.answer-follows-new-level", "decision: Store, ID, baud, reset",
       "0x03 = 1 at response level 1 is not answered: the answer follows 0x11 after the reset "
       "(default level 0)")
def reset_answer(ctx):
    i = ctx.ids[0]
    saved = _settings(ctx, i)
    try:
        ctx.write_ok(i, 0x11, bytes([saved[0x11][0] | 0x08]))
        ctx.silent(fr.write(i, 0x03, b"\x01"), "0x03 = 1: no answer at the reset's level 0")
        ctx.level.pop(i, None)
        expect(ctx.read_int(i, 0x11) == 0x02, "0x11 = 0x%02X after reset" % ctx.read_int(i, 0x11))
    finally:
        ctx.restore(i, saved)


@check("reset.bad-level", "§5.1 0x03 (1 or 2), §4 bit 6",
       "0x03 = 0 or 3: bit 6, nothing reset")
def reset_bad(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x12])
    try:
        ctx.write_ok(i, 0x12, spec.u16(345))
        for v in (0, 3, 255):
            ctx.write_fails(i, 0x03, spec.u8(v), spec.BIT_FAILED)
        expect(ctx.read_int(i, 0x12) == 345, "0x12 reset by a bad level")
    finally:
        ctx.restore(i, saved)
