# SPDX-License-Identifier: Apache-2.0
"""§2 frames and §3 commands, one servo at a time (multi-servo ones: checks_bus)."""
import spec
from ctx import Fail, Skip, check, expect, hexs
from wire import fr

# §2 "Worked frames", copied from docs/protocol.md: the master's encoder must
# produce them byte for byte, or every other check would test the wrong thing.
WORKED = [
    ("ping ID 1", lambda: fr.ping(1), "F9 FF 01 02 01 FB"),
    ("its short response", lambda: fr.encode_status(1, 0), "F9 F5 01 02 00 FC"),
    ("read protocol version", lambda: fr.read(1, 0x0B), "F9 FF 01 03 02 0B EE"),
    ("read servo status", lambda: fr.read(1, 0x01), "F9 FF 01 03 02 01 F8"),
    ("its response", lambda: fr.encode_response(1, 2, 1, b"\x00\x05"),
     "F9 F5 01 05 02 01 00 05 F1"),
    ("write 0x65", lambda: fr.write(1, 0x65, bytes.fromhex("8403E803")),
     "F9 FF 01 07 03 65 84 03 E8 03 1D"),
    ("restart", lambda: fr.write(1, 0x02, spec.RESTART_MAGIC), "F9 FF 01 07 03 02 E1 E2 E3 E4 68"),
    ("multi-ID torque", lambda: fr.encode_command(0xFE, 0x83, 0x64, bytes.fromhex("01010202020302")),
     "F9 FF FE 0A 83 64 01 01 02 02 02 03 02 03"),
    ("multi-ID 0x65", lambda: fr.encode_command(
        0xFE, 0x83, 0x65, bytes.fromhex("04 05 0000 E803 07 5A00 E803 09 A6FF E803")),
     "F9 FF FE 13 83 65 04 05 00 00 E8 03 07 5A 00 E8 03 09 A6 FF E8 03 2D"),
    ("multi-ID 0x65, time omitted", lambda: fr.encode_command(
        0xFE, 0x83, 0x65, bytes.fromhex("02 05 0000 07 5A00 09 A6FF")),
     "F9 FF FE 0D 83 65 02 05 00 00 07 5A 00 09 A6 FF F6"),
    ("sync write torque ID 1", lambda: fr.encode_command(1, 0x04, 0x64, b"\x02"),
     "F9 FF 01 04 04 64 02 90"),
    ("sync write torque ID 3", lambda: fr.encode_command(3, 0x04, 0x64, b"\x02"),
     "F9 FF 03 04 04 64 02 8E"),
    ("sync execute", lambda: fr.encode_command(0xFE, 0x84), "F9 FF FE 02 84 7B"),
    ("sync write 0x65 to 9", lambda: fr.encode_command(9, 0x04, 0x65, bytes.fromhex("A6FFE803")),
     "F9 FF 09 07 04 65 A6 FF E8 03 F6"),
]


@check("frame.worked-examples", "§2", "the master's encoder reproduces every worked frame of §2")
def worked_frames(ctx):
    for what, make, want in WORKED:
        got = make()
        expect(got == bytes.fromhex(want), "%s: encoded %s, §2 says %s" % (what, hexs(got), want))


@check("cmd.ping", "§3 0x01, §2", "each servo answers a ping with F9 F5 id 02 status cs")
def cmd_ping(ctx):
    for i in ctx.ids:
        r = ctx.ask(fr.ping(i))
        expect(len(r) == 1, "ping %d: %d answers" % (i, len(r)))
        f = r[0]
        raw = f.to_bytes()
        expect(raw[:2] == b"\xF9\xF5" and raw[2] == i and raw[3] == 2 and len(raw) == 6,
               "ping %d answered %s" % (i, hexs(raw)))


@check("cmd.read", "§3 0x02", "a read answers F9 F5 id len 02 adr value: 0x0B of each servo")
def cmd_read(ctx):
    for i in ctx.ids:
        f = ctx.read_frame(i, 0x0B)
        raw = f.to_bytes()
        expect(raw[:3] == bytes([0xF9, 0xF5, i]) and raw[4:6] == b"\x02\x0B" and raw[3] == 7,
               "read 0x0B of %d answered %s (expected length 7: cmd, adr, 4 value bytes, cs)"
               % (i, hexs(raw)))


@check("cmd.write.level0", "§3 0x03, §5.1 0x11 bit 3",
       "at response level 0 a write is not answered and takes effect")
def cmd_write_level0(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x11, 0x12])
    try:
        ctx.write_ok(i, 0x11, bytes([saved[0x11][0] & ~0x08 & 0xFF]))
        new = 300 if spec.to_int(saved[0x12]) != 300 else 310
        ctx.silent(fr.write(i, 0x12, spec.u16(new)), "a write at response level 0: no answer")
        expect(ctx.read_int(i, 0x12) == new, "0x12 not written")
    finally:
        ctx.restore(i, saved)


@check("cmd.write.level1", "§3 0x03, §5.1 0x11 bit 3",
       "at response level 1 a write to the own ID answers a short response; broadcast does not")
def cmd_write_level1(ctx):
    i = ctx.ids[0]
    saved = {j: ctx.snapshot(j, [0x11, 0x12]) for j in ctx.ids}
    try:
        for j in ctx.ids:
            ctx.write_ok(j, 0x11, bytes([saved[j][0x11][0] | 0x08]))
        r = ctx.ask(fr.write(i, 0x12, spec.u16(250)))
        expect(len(r) == 1 and r[0].id == i and r[0].is_status and not r[0].status & spec.BITS_56,
               "write at level 1 answered %s" % [hexs(f.to_bytes()) for f in r])
        ctx.silent(fr.write(spec.ID_BROADCAST, 0x12, spec.u16(260)),
                   "a broadcast write at response level 1: no answer (§3)")
        for j in ctx.ids:
            expect(ctx.read_int(j, 0x12) == 260, "servo %d: broadcast write not executed" % j)
    finally:
        for j in ctx.ids:
            ctx.restore(j, saved[j])


@check("cmd.sync-write", "§3 0x04/0x84",
       "0x04 is buffered (not applied, not answered) until 0x84 broadcast executes it")
def cmd_sync(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x12])
    try:
        new = 330 if spec.to_int(saved[0x12]) != 330 else 340
        ctx.silent(fr.encode_command(i, 0x04, 0x12, spec.u16(new)), "0x04: no answer")
        # the read is a command to this servo and would clear the buffer: so
        # only execute then read (the buffering itself: checks_bus)
        ctx.silent(fr.encode_command(spec.ID_BROADCAST, 0x84), "0x84: no answer")
        expect(ctx.read_int(i, 0x12) == new, "0x84 did not execute the buffered write")
        ctx.clean(i)
    finally:
        ctx.restore(i, saved)


@check("decision:cmd.sync-execute.own-id", "decision: Sync write",
       "0x84 sent to the servo's own ID executes its buffer too")
def cmd_sync_own(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x12])
    try:
        new = 350 if spec.to_int(saved[0x12]) != 350 else 360
        ctx.silent(fr.encode_command(i, 0x04, 0x12, spec.u16(new)), "0x04: no answer")
        ctx.silent(fr.encode_command(i, 0x84), "0x84: no answer")
        expect(ctx.read_int(i, 0x12) == new, "0x84 to the own ID did not execute")
    finally:
        ctx.restore(i, saved)


@check("cmd.multi-write", "§3 0x83, §2 worked frame",
       "the §2 frame 'multi-ID write torque on' (0x64 = 1 on each listed servo), not answered")
def cmd_multi_write(ctx):
    saved = {i: ctx.snapshot(i, [0x64]) for i in ctx.ids}
    try:
        params = bytes([1]) + b"".join(bytes([i, 1]) for i in ctx.ids)
        ctx.silent(fr.encode_command(spec.ID_BROADCAST, 0x83, 0x64, params), "0x83: no answer")
        for i in ctx.ids:
            expect(ctx.read_int(i, 0x64) == 1, "servo %d: 0x64 not 1 after 0x83" % i)
            expect(not ctx.status(i) & spec.BITS_56, "servo %d: 0x83 set bit 5/6" % i)
    finally:
        for i in ctx.ids:
            ctx.restore(i, saved[i])


@check("cmd.multi-write.unlisted", "§3 0x83", "a servo not in the 0x83 list changes nothing")
def cmd_multi_unlisted(ctx):
    if len(ctx.ids) < 2:
        raise Skip("needs two servos (--ids)")
    a, b = ctx.ids[0], ctx.ids[1]
    saved = {i: ctx.snapshot(i, [0x64]) for i in (a, b)}
    try:
        for i in (a, b):
            ctx.write_ok(i, 0x64, b"\x00")
        ctx.silent(fr.encode_command(spec.ID_BROADCAST, 0x83, 0x64, bytes([1, a, 1])), "0x83")
        expect(ctx.read_int(a, 0x64) == 1, "listed servo %d: 0x64 not 1" % a)
        expect(ctx.read_int(b, 0x64) == 0, "unlisted servo %d: 0x64 changed" % b)
    finally:
        for i in (a, b):
            ctx.restore(i, saved[i])


@check("cmd.multi-write.bad-address", "§3 0x83 (0x64..0x6F only), §4 bit 5",
       "0x83 naming an address outside 0x64 0x65 0x66 0x68 0x6E 0x6F: nothing runs, bit 5")
def cmd_multi_bad_addr(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x5B])
    try:
        ctx.clean(i)
        val = spec.to_int(saved[0x5B])
        new = val - 1 if val > 0 else 1
        ctx.silent(fr.encode_command(spec.ID_BROADCAST, 0x83, 0x5B, bytes([2, i]) + spec.u16(new)),
                   "0x83")
        expect(ctx.read_int(i, 0x5B) == val, "0x5B changed by 0x83, which does not allow it")
        st = ctx.status(i)
        expect(st & spec.BITS_56 == spec.BIT_EXCEPTION, "next ping status 0x%02X, expected bit 5" % st)
    finally:
        ctx.restore(i, saved)


@check("decision:cmd.multi-read", "decision: Multi-ID read 0x82",
       "0x82: broadcast F9 FF FE len 82 adr id1..idn: each listed servo answers its 0x02 read "
       "answer, in list order")
def cmd_multi_read(ctx):
    order = list(reversed(ctx.ids)) if len(ctx.ids) > 1 else list(ctx.ids)
    frame = fr.encode_command(spec.ID_BROADCAST, 0x82, 0x0B, bytes(order))
    r = ctx.ask(frame, len(order), timeout=ctx.timeout + 0.5)
    if not r:
        for i in order:
            st = ctx.status(i)
            if st & spec.BIT_EXCEPTION:
                raise Fail("no answer; servo %d reports bit 5 (0x82 unsupported)" % i)
        raise Fail("no answer to %s" % hexs(frame))
    expect([f.id for f in r] == order, "answers from %s, expected %s (list order)"
           % ([f.id for f in r], order))
    for f in r:
        expect(not f.is_status and f.cmd == 0x02 and f.addr == 0x0B and len(f.params) == 4,
               "servo %d answered %s, expected its 0x02 read answer" % (f.id, hexs(f.to_bytes())))


@check("decision:cmd.multi-read.subset", "decision: Multi-ID read 0x82",
       "0x82 listing some servos: only they answer; an unlisted servo stays silent")
def cmd_multi_read_subset(ctx):
    if len(ctx.ids) < 2:
        raise Skip("needs two servos (--ids)")
    listed = [ctx.ids[-1]]
    frame = fr.encode_command(spec.ID_BROADCAST, 0x82, 0x12, bytes(listed))
    r = ctx.wire.transact(frame, None, ctx.timeout + 0.3, quiet=ctx.quiet + 0.1)
    expect([f.id for f in r] == listed, "answers from %s, expected %s" % ([f.id for f in r], listed))


@check("decision:cmd.factory-test", "decision: Malformed frames",
       "0x7E factory test (document not provided): no answer, bit 5 at the next ping")
def cmd_undocumented(ctx):
    i = ctx.ids[0]
    for cmd in (0x7E,):
        ctx.clean(i)
        ctx.silent(fr.encode_command(i, cmd, 0x00, b""), "command 0x%02X: no answer" % cmd)
        st = ctx.status(i)
        expect(st & spec.BITS_56 == spec.BIT_EXCEPTION,
               "command 0x%02X: next ping status 0x%02X, expected bit 5" % (cmd, st))


@check("decision:cmd.write.level-change-answer", "decision: Response level of a write",
       "a write of 0x11 is answered at the response level it sets: 0 -> 1 answered, 1 -> 0 not")
def cmd_level_change(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x11])
    try:
        lvl0 = bytes([saved[0x11][0] & 0xF7])
        lvl1 = bytes([saved[0x11][0] | 0x08])
        ctx.write_ok(i, 0x11, lvl0)
        r = ctx.ask(fr.write(i, 0x11, lvl1))
        expect(len(r) == 1 and r[0].id == i and r[0].is_status and not r[0].status & spec.BITS_56,
               "0x11 level 0 -> 1 answered %s, expected a short response" % [hexs(f.to_bytes()) for f in r])
        ctx.silent(fr.write(i, 0x11, lvl0), "0x11 level 1 -> 0: no answer")
        ctx.level[i] = 0
    finally:
        ctx.level.pop(i, None)
        ctx.restore(i, saved)


@check("decision:cmd.multi-read.absent-id", "decision: Multi-ID read 0x82",
       "0x82 listing an ID nobody has between two servos: its slot stays silent, the others "
       "answer in their list positions")
def cmd_multi_read_absent(ctx):
    if len(ctx.ids) < 2:
        raise Skip("needs two servos (--ids)")
    absent = ctx.other_id()
    order = [ctx.ids[1], absent, ctx.ids[0]]
    r = ctx.ask(fr.encode_command(spec.ID_BROADCAST, 0x82, 0x12, bytes(order)), 2,
                timeout=ctx.timeout + 0.5)
    expect([f.id for f in r] == [ctx.ids[1], ctx.ids[0]],
           "answers from %s, expected %s" % ([f.id for f in r], [ctx.ids[1], ctx.ids[0]]))
