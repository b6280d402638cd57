# SPDX-License-Identifier: Apache-2.0
"""§1/§3 several servos on one bus: super ID (slots, answer order), broadcast,
sync write / execute interleaving, the other servos' answers on the wire."""
import spec
from ctx import Skip, check, expect, hexs
from wire import fr


def _super(ctx, frame, n_extra=0.3):
    """All answers to a super-ID request: wait for the listed servos, then
    for quiet (other servos may share the bus)."""
    got = ctx.wire.transact(frame, None, ctx.timeout + n_extra + 0.01 * 255, quiet=ctx.quiet + 0.05)
    return got


def _order(ctx, got, what):
    ids = [f.id for f in got]
    mine = [i for i in ids if i in ctx.ids]
    expect(sorted(set(mine)) == sorted(ctx.ids), "%s: answers from %s, expected each of %s"
           % (what, ids, ctx.ids))
    expect(len(mine) == len(ctx.ids), "%s: duplicate answers %s" % (what, ids))
    expect(ids == sorted(ids), "%s: answer order %s, the slots are in ID order" % (what, ids))


@check("super.ping", "§1 ID 253, §3 Decision (slots)",
       "a super-ID ping: every servo answers a short response, in ID order (its slot)")
def super_ping(ctx):
    got = _super(ctx, fr.ping(spec.ID_SUPER))
    _order(ctx, got, "super-ID ping")
    expect(all(f.is_status for f in got), "not all short responses: %s" % got)


@check("super.read", "§1 ID 253, §3 Decision (slots)",
       "a super-ID read of 0x46 (the longest answer, i16 or i32): every servo answers its "
       "read answer, in ID order")
def super_read(ctx):
    got = _super(ctx, fr.read(spec.ID_SUPER, 0x46))
    _order(ctx, got, "super-ID read 0x46")
    expect(all(not f.is_status and f.cmd == 2 and f.addr == 0x46 and len(f.params) in (2, 4)
               for f in got), "answers %s" % [hexs(f.to_bytes()) for f in got])


@check("super.read.repeated", "§3 Decision (slots)",
       "20 super-ID pings and reads in a row: every answer in its slot, in ID order")
def super_repeated(ctx):
    for n in range(20):
        frame = fr.ping(spec.ID_SUPER) if n % 2 else fr.read(spec.ID_SUPER, 0x12)
        got = ctx.ask(frame, len(ctx.ids), timeout=ctx.timeout + 0.3)
        ids = [f.id for f in got]
        expect(ids == sorted(ctx.ids), "round %d: answers %s, expected %s" % (n, ids, sorted(ctx.ids)))


@check("super.read.unknown-address", "§3, §4 bit 5",
       "a super-ID read of a reserved address: each servo answers bit 5 in its slot")
def super_read_bad(ctx):
    got = _super(ctx, fr.read(spec.ID_SUPER, 0x05))
    _order(ctx, got, "super-ID read 0x05")
    expect(all(f.is_status and f.status & spec.BIT_EXCEPTION for f in got),
           "answers %s" % [hexs(f.to_bytes()) for f in got])
    for i in ctx.ids:
        ctx.clean(i)


@check("decision:super.write-ignored", "decision: Super ID",
       "a write to the super ID: nobody answers, nothing changes, status stays clean")
def super_write(ctx):
    i = ctx.ids[0]
    before = ctx.read(i, 0x12)
    ctx.silent(fr.write(spec.ID_SUPER, 0x12, spec.u16(spec.to_int(before) + 7)))
    expect(ctx.read(i, 0x12) == before, "0x12 changed by a super-ID write")
    expect(not ctx.status(i) & spec.BITS_56, "status bits set by a super-ID write")


@check("broadcast.ping-read", "§1 ID 254, §3",
       "broadcast ping and broadcast read: nobody answers")
def broadcast_silent(ctx):
    ctx.silent(fr.ping(spec.ID_BROADCAST), "broadcast ping: no answer")
    ctx.silent(fr.read(spec.ID_BROADCAST, 0x0B), "broadcast read: no answer")
    for i in ctx.ids:
        expect(not ctx.status(i) & spec.BITS_56, "servo %d: status bits set" % i)


@check("broadcast.write", "§3 (write with broadcast: executed, no answer)",
       "a broadcast write is executed by every servo, unanswered")
def broadcast_write(ctx):
    saved = {i: ctx.snapshot(i, [0x12]) for i in ctx.ids}
    try:
        ctx.silent(fr.write(spec.ID_BROADCAST, 0x12, spec.u16(400)))
        got = ctx.ask(fr.read(spec.ID_SUPER, 0x12), len(ctx.ids), timeout=ctx.timeout + 0.3)
        expect(sorted(f.id for f in got) == sorted(ctx.ids) and
               all(f.params == spec.u16(400) for f in got),
               "super-ID read back: %s" % [hexs(f.to_bytes()) for f in got])
    finally:
        for i in ctx.ids:
            ctx.restore(i, saved[i])


@check("bus.response-inside-frame", "§2",
       "a servo's response frame whose value holds a whole command frame is skipped whole")
def bus_embedded(ctx):
    i = ctx.ids[0]
    other = ctx.ids[1] if len(ctx.ids) > 1 else 100
    fake = fr.encode_response(other, 0x02, 0x0A, fr.ping(i))
    ctx.silent(fake, "a response frame on the wire: nobody answers")
    expect(not ctx.status(i) & spec.BITS_56, "status bits set")


@check("sync.interleaved", "§3 Reading (frames for other IDs do not clear the buffer)",
       "0x04 for each servo in turn, then one broadcast 0x84: every servo applies its own value")
def sync_interleaved(ctx):
    if len(ctx.ids) < 2:
        raise Skip("needs two servos (--ids)")
    saved = {i: ctx.snapshot(i, [0x12]) for i in ctx.ids}
    try:
        want = {i: 210 + 10 * n for n, i in enumerate(ctx.ids)}
        for i in ctx.ids:
            ctx.silent(fr.encode_command(i, 0x04, 0x12, spec.u16(want[i])), "0x04: no answer")
        ctx.silent(fr.encode_command(spec.ID_BROADCAST, 0x84), "0x84: no answer")
        for i in ctx.ids:
            got = ctx.read_int(i, 0x12)
            expect(got == want[i], "servo %d: 0x12 = %d, expected its buffered %d" % (i, got, want[i]))
    finally:
        for i in ctx.ids:
            ctx.restore(i, saved[i])


@check("sync.cleared-by-own-command", "§3 0x04 (any other command to this servo clears it)",
       "0x04 to two servos, a read of the first: 0x84 applies only the second's buffer")
def sync_cleared(ctx):
    if len(ctx.ids) < 2:
        raise Skip("needs two servos (--ids)")
    a, b = ctx.ids[0], ctx.ids[1]
    saved = {i: ctx.snapshot(i, [0x12]) for i in (a, b)}
    try:
        va, vb = spec.to_int(saved[a][0x12]), spec.to_int(saved[b][0x12])
        ctx.send(fr.encode_command(a, 0x04, 0x12, spec.u16(va + 11)))
        ctx.send(fr.encode_command(b, 0x04, 0x12, spec.u16(vb + 11)))
        expect(ctx.read_int(a, 0x12) == va, "servo %d applied 0x04 before 0x84" % a)
        ctx.silent(fr.encode_command(spec.ID_BROADCAST, 0x84), "0x84: no answer")
        expect(ctx.read_int(a, 0x12) == va, "servo %d: the read did not clear its buffer" % a)
        expect(ctx.read_int(b, 0x12) == vb + 11, "servo %d: its buffer was lost" % b)
    finally:
        for i in (a, b):
            ctx.restore(i, saved[i])


@check("sync.overwrite", "§3 0x04 (a second 0x04 overwrites the buffer)",
       "two 0x04 to one servo: 0x84 applies the second")
def sync_overwrite(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x12])
    try:
        v = spec.to_int(saved[0x12])
        ctx.send(fr.encode_command(i, 0x04, 0x12, spec.u16(v + 21)))
        ctx.send(fr.encode_command(i, 0x04, 0x12, spec.u16(v + 22)))
        ctx.silent(fr.encode_command(spec.ID_BROADCAST, 0x84), "0x84: no answer")
        expect(ctx.read_int(i, 0x12) == v + 22, "0x12 = %d, expected %d" % (ctx.read_int(i, 0x12), v + 22))
    finally:
        ctx.restore(i, saved)


@check("decision:sync.execute-empty", "decision: Sync write (0x84 with an empty buffer)",
       "0x84 with nothing buffered does nothing and sets no status bit")
def sync_empty(ctx):
    i = ctx.ids[0]
    ctx.clean(i)
    before = ctx.read(i, 0x12)
    ctx.silent(fr.encode_command(spec.ID_BROADCAST, 0x84))
    ctx.silent(fr.encode_command(spec.ID_BROADCAST, 0x84))
    expect(ctx.read(i, 0x12) == before, "0x12 changed")
    expect(not ctx.status(i) & spec.BITS_56, "status bits set by an empty 0x84")
