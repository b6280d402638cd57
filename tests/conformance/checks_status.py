# SPDX-License-Identifier: Apache-2.0
"""§4 status byte: bits 5 and 6 set and cleared (docs/protocol.md §4, and the life
cycle docs/protocol-decisions.md gives them where §4's "cleared on the next
command" is open), bit 7 while a rotation runs, bits 0..4 clean on a servo
without a fault."""
import time

import spec
from ctx import Skip, check, expect, hexs
from wire import fr

BAD_VALUE = (0x13, spec.u16(1001))  # §5.1 0x13 is 0..1000


def _bad_checksum_ping(i):
    f = bytearray(fr.ping(i))
    f[-1] ^= 0xFF
    return bytes(f)


def _level0(ctx, i):
    """Puts servo i at response level 0 and returns what to restore."""
    saved = ctx.snapshot(i, [0x11])
    ctx.write_ok(i, 0x11, bytes([saved[0x11][0] & 0xF7]))
    return saved


@check("status.clean", "§4, §5.2 0x35/0x36",
       "every servo: status bits 0..4 and 0x35, 0x36 are 0 (no fault, no protection)")
def status_clean(ctx):
    for i in ctx.ids:
        ctx.clean(i)
        st = ctx.status(i)
        expect(st & 0x1F == 0, "servo %d status 0x%02X" % (i, st))
        expect(ctx.read_int(i, 0x35) == 0, "servo %d: 0x35 = %d" % (i, ctx.read_int(i, 0x35)))
        expect(ctx.read_int(i, 0x36) == 0, "servo %d: 0x36 = %d" % (i, ctx.read_int(i, 0x36)))


@check("status.bit6.bad-value", "§4 bit 6",
       "a write of an out-of-range value: bit 6 at the next ping, clear at the one after")
def status_bit6(ctx):
    i = ctx.ids[0]
    saved = _level0(ctx, i)
    try:
        ctx.clean(i)
        ctx.silent(fr.write(i, *BAD_VALUE))
        st = ctx.status(i)
        expect(st & spec.BITS_56 == spec.BIT_FAILED, "next ping 0x%02X, expected bit 6" % st)
        st = ctx.status(i)
        expect(not st & spec.BITS_56, "second ping 0x%02X, expected bits 5/6 clear" % st)
    finally:
        ctx.restore(i, saved)


@check("status.bit5.unknown-address", "§4 bit 5",
       "a read of an unsupported address answers bit 5 itself; the next ping is clear")
def status_bit5_addr(ctx):
    i = ctx.ids[0]
    ctx.clean(i)
    f = ctx.read_frame(i, 0x05)
    expect(f.is_status and f.status & spec.BITS_56 == spec.BIT_EXCEPTION,
           "read 0x05 answered %s" % hexs(f.to_bytes()))
    st = ctx.status(i)
    expect(not st & spec.BITS_56, "next ping 0x%02X, expected clear" % st)


@check("status.bit5.checksum", "§4 bit 5 and its Decision",
       "a frame with a bad checksum for our ID: no answer, bit 5 at the next ping, then clear")
def status_bit5_checksum(ctx):
    i = ctx.ids[0]
    ctx.clean(i)
    ctx.silent(_bad_checksum_ping(i), "a bad checksum: no answer")
    st = ctx.status(i)
    expect(st & spec.BITS_56 == spec.BIT_EXCEPTION, "next ping 0x%02X, expected bit 5" % st)
    st = ctx.status(i)
    expect(not st & spec.BITS_56, "second ping 0x%02X, expected clear" % st)


@check("status.bit5.unknown-command", "§4 bit 5",
       "an unknown command (0x50): no answer, bit 5 at the next ping")
def status_bit5_cmd(ctx):
    i = ctx.ids[0]
    ctx.clean(i)
    ctx.silent(fr.encode_command(i, 0x50, 0x12, b""), "unknown command 0x50: no answer")
    st = ctx.status(i)
    expect(st & spec.BITS_56 == spec.BIT_EXCEPTION, "next ping 0x%02X, expected bit 5" % st)


@check("decision:status.kept-until-reported", "decision: Status bits 5 and 6 (rules 2-4)",
       "bit 6 of an unanswered write survives a read (whose answer has no status byte) and "
       "shows in the next ping")
def status_kept(ctx):
    i = ctx.ids[0]
    saved = _level0(ctx, i)
    try:
        ctx.clean(i)
        ctx.send(fr.write(i, *BAD_VALUE))
        ctx.read(i, 0x12)
        st = ctx.status(i)
        expect(st & spec.BITS_56 == spec.BIT_FAILED, "ping after the read 0x%02X, expected bit 6" % st)
        expect(not ctx.status(i) & spec.BITS_56, "not cleared by the ping that reported it")
    finally:
        ctx.restore(i, saved)


@check("decision:status.read-0x01-reports", "decision: Status bits 5 and 6 (rule 3)",
       "a read of 0x01 reports the unreported bits in its first byte and clears them")
def status_read01(ctx):
    i = ctx.ids[0]
    saved = _level0(ctx, i)
    try:
        ctx.clean(i)
        ctx.send(fr.write(i, *BAD_VALUE))
        v = ctx.read(i, 0x01)
        expect(v[0] & spec.BITS_56 == spec.BIT_FAILED, "0x01 reads %s, expected bit 6" % hexs(v))
        st = ctx.status(i)
        expect(not st & spec.BITS_56, "ping after 0x01: 0x%02X, expected clear" % st)
    finally:
        ctx.restore(i, saved)


@check("decision:status.accumulate", "decision: Status bits 5 and 6 (rule 2)",
       "a failed write and an unknown command, both unanswered: the next ping shows bits 5 and 6")
def status_accumulate(ctx):
    i = ctx.ids[0]
    saved = _level0(ctx, i)
    try:
        ctx.clean(i)
        ctx.send(fr.write(i, *BAD_VALUE))
        ctx.silent(fr.encode_command(i, 0x50, 0x12, b""))
        st = ctx.status(i)
        expect(st & spec.BITS_56 == spec.BITS_56, "ping 0x%02X, expected bits 5 and 6" % st)
    finally:
        ctx.restore(i, saved)


@check("decision:status.level1-own-outcome", "decision: Status bits 5 and 6 (rule 4)",
       "at response level 1 a good write answers 0 although a checksum error waits; the "
       "next ping reports it")
def status_own(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x11, 0x12])
    try:
        ctx.write_ok(i, 0x11, bytes([saved[0x11][0] | 0x08]))
        ctx.clean(i)
        ctx.silent(_bad_checksum_ping(i))
        r = ctx.ask(fr.write(i, 0x12, saved[0x12]))
        expect(r and r[0].is_status and not r[0].status & spec.BITS_56,
               "the write answered %s, expected status 0" % [hexs(f.to_bytes()) for f in r])
        st = ctx.status(i)
        expect(st & spec.BITS_56 == spec.BIT_EXCEPTION, "next ping 0x%02X, expected bit 5" % st)
    finally:
        ctx.restore(i, saved)


@check("decision:status.broadcast-failure", "decision: Status bits 5 and 6 (rule 5)",
       "a broadcast write of a bad value (unanswered): bit 6 at each servo's next ping")
def status_broadcast(ctx):
    for i in ctx.ids:
        ctx.clean(i)
    ctx.silent(fr.write(spec.ID_BROADCAST, *BAD_VALUE))
    for i in ctx.ids:
        st = ctx.status(i)
        expect(st & spec.BITS_56 == spec.BIT_FAILED, "servo %d: ping 0x%02X, expected bit 6" % (i, st))


@check("decision:status.other-ids", "decision: Status bits 5 and 6 (rule 6)",
       "bad frames for another ID change nothing on this servo")
def status_other(ctx):
    if len(ctx.ids) < 2:
        raise Skip("needs two servos (--ids)")
    a, b = ctx.ids[0], ctx.ids[1]
    ctx.clean(a)
    ctx.clean(b)
    ctx.send(_bad_checksum_ping(b))
    ctx.silent(fr.encode_command(b, 0x50, 0x12, b""))
    st = ctx.status(a)
    expect(not st & spec.BITS_56, "servo %d: 0x%02X after bad frames for %d" % (a, st, b))
    ctx.clean(b)


def _pos(ctx, i):
    return ctx.read_int(i, 0x46)


@check("status.bit7.running", "§4 bit 7, §5.4 0x64/0x65, §5.3 0x4D",
       "0x65 with the torque on: bit 7 while the move runs, clear when it ends near the target")
def status_running(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x64])
    try:
        ctx.write_ok(i, 0x64, b"\x02")
        start = _pos(ctx, i)
        target = start + 100 if start < 500 else start - 100  # 10.0 deg, inside any travel
        ctx.write_ok(i, 0x65, spec.i16(target) + spec.u16(600))
        seen_running = False
        end = time.monotonic() + 5.0 * ctx.opts.time_scale
        while time.monotonic() < end:
            st = ctx.status(i)
            if st & spec.BIT_RUNNING:
                seen_running = True
            elif seen_running:
                break
        expect(seen_running, "bit 7 never seen during a 600 ms move")
        expect(not ctx.status(i) & spec.BIT_RUNNING, "bit 7 still set 5 s after a 600 ms move")
        p = _pos(ctx, i)
        expect(abs(p - target) <= 20, "stopped at %d, target %d (0.1 deg)" % (p, target))
        expect(ctx.read_int(i, 0x4D) >= 300, "0x4D rotation time %d ms" % ctx.read_int(i, 0x4D))
        ctx.write_ok(i, 0x65, spec.i16(start) + spec.u16(300))  # back where it was
        time.sleep(0.6 * ctx.opts.time_scale)
    finally:
        ctx.write(i, 0x64, b"\x00")
        ctx.restore(i, saved)
