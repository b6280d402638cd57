# SPDX-License-Identifier: Apache-2.0
"""The bad-input catalog: bad checksums, truncated frames, bad lengths,
unknown commands, wrong-length writes, noise between frames, invalid IDs.
Each input has a defined outcome (docs/protocol.md §2, §4, §7 and its Decisions);
after each, the servo must still answer a clean frame."""
import time

import spec
from ctx import check, expect, hexs
from wire import fr


def _pause(ctx):
    # Longer than any inter-byte gap rule (§7 Decision: a few byte times;
    # emulated boards ride out host stalls with a 20 ms floor).
    time.sleep(ctx.opts.pause_ms / 1000.0)


def _still_answers(ctx, i):
    st = ctx.ping(i)
    expect(st is not None, "servo %d does not answer a clean ping afterwards" % i)
    ctx.clean(i)


@check("bad.checksum.write", "§2 checksum, §4 Decision",
       "a write with a bad checksum (each of 3 corruptions): no answer, not applied")
def bad_checksum_write(ctx):
    i = ctx.ids[0]
    before = ctx.read(i, 0x12)
    good = fr.write(i, 0x12, spec.u16(spec.to_int(before) + 5))
    for n in (1, 0x80, 0xFF):
        f = bytearray(good)
        f[-1] ^= n
        ctx.silent(bytes(f), "a bad checksum: no answer")
        expect(ctx.read(i, 0x12) == before, "write with checksum ^ 0x%02X applied" % n)
        ctx.clean(i)


@check("bad.checksum.body", "§2 checksum",
       "a read whose address byte was corrupted on the wire (checksum no longer fits): no answer")
def bad_checksum_body(ctx):
    i = ctx.ids[0]
    f = bytearray(fr.read(i, 0x0B))
    f[5] ^= 0x01
    ctx.silent(bytes(f), "a corrupted frame: no answer")
    _still_answers(ctx, i)


@check("bad.truncated", "§7 Decision (inter-byte gap)",
       "the first 2..n-1 bytes of a read, then silence: no answer; the next frame is answered")
def bad_truncated(ctx):
    i = ctx.ids[0]
    f = fr.read(i, 0x0B)
    for cut in range(2, len(f)):
        ctx.send(f[:cut])
        _pause(ctx)
        got = ctx.wire.collect(None, 0.2, quiet=0.01)
        expect(not got, "%s (truncated) answered" % hexs(f[:cut]))
        r = ctx.ask(fr.read(i, 0x0B))
        expect(r and not r[0].is_status and r[0].addr == 0x0B,
               "after %d bytes of a read and a pause, the next read got %s"
               % (cut, [hexs(x.to_bytes()) for x in r]))
    ctx.clean(i)


@check("decision:bad.truncated-resync", "decision: Inter-byte gap (resynchronising)",
       "a truncated read followed at once by a ping: the ping is answered")
def bad_truncated_resync(ctx):
    i = ctx.ids[0]
    for cut in (3, 4, 5, 6):
        r = ctx.ask(fr.read(i, 0x0B)[:cut] + fr.ping(i))
        expect(r and r[0].id == i and r[0].is_status,
               "cut %d: answered %s" % (cut, [hexs(x.to_bytes()) for x in r]))
        ctx.clean(i)


@check("bad.paused-frame", "§7 Decision (inter-byte gap)",
       "a ping whose bytes stop after 3 for longer than the gap, then go on: dropped; the next ping is answered")
def bad_paused_frame(ctx):
    i = ctx.ids[0]
    f = fr.ping(i)
    ctx.send(f[:3])
    _pause(ctx)
    ctx.silent(f[3:], "the rest of a ping after a pause: no answer")
    _still_answers(ctx, i)


@check("bad.length", "§2 (2 <= length <= 252)",
       "frames with length 0, 1, 253, 254, 255: no answer; the next frame is answered")
def bad_length(ctx):
    i = ctx.ids[0]
    for n in (0, 1, 253, 254, 255):
        core = bytes([i, n, 0x01])
        ctx.send(b"\xF9\xFF" + core + bytes([~sum(core) & 0xFF]))
        _pause(ctx)
        got = ctx.wire.collect(None, 0.2, quiet=0.01)
        expect(not got, "length %d answered %s" % (n, [hexs(x.to_bytes()) for x in got]))
        expect(ctx.ping(i) is not None, "no answer after a frame of length %d" % n)
    ctx.clean(i)


@check("bad.length-mismatch", "§2 length",
       "a ping whose length claims one byte more or less than it has: not answered as a ping")
def bad_length_mismatch(ctx):
    i = ctx.ids[0]
    for n in (3, 4):
        core = bytes([i, n, 0x01])
        ctx.send(b"\xF9\xFF" + core + bytes([~sum(core) & 0xFF]))
        _pause(ctx)
        got = ctx.wire.collect(None, 0.2, quiet=0.01)
        expect(not got, "length %d answered %s" % (n, [hexs(x.to_bytes()) for x in got]))
    _still_answers(ctx, i)


@check("bad.unknown-commands", "§4 bit 5",
       "commands 0x00, 0x05, 0x50, 0x81, 0x85, 0xFF: no answer, bit 5 at the next ping")
def bad_unknown(ctx):
    i = ctx.ids[0]
    for cmd in (0x00, 0x05, 0x50, 0x81, 0x85, 0xFF):
        ctx.clean(i)
        ctx.silent(fr.encode_command(i, cmd, 0x12, b""), "command 0x%02X" % cmd)
        st = ctx.status(i)
        expect(st & spec.BITS_56 == spec.BIT_EXCEPTION, "command 0x%02X: ping 0x%02X" % (cmd, st))


@check("bad.noise", "§2 (header F9 FF)",
       "bytes that are no frame (with stray F9s) before and between two pings: both answered")
def bad_noise(ctx):
    i = ctx.ids[0]
    for noise in (b"\x00\x55\xAA\xFF", b"\xF9", b"\xF9\xF9", b"\xF9\x00\xF9\xF5", b"\xFF\xF9\x01",
                  bytes(range(0, 0xF9, 7))):
        # one exchange at a time: a frame sent while an answer is on the
        # half-duplex wire would collide with it
        for where in ("before", "between"):
            r = ctx.ask(noise + fr.ping(i))
            expect(len(r) == 1 and r[0].id == i and r[0].is_status,
                   "noise %s %s pings: answers %s" % (hexs(noise), where, [hexs(f.to_bytes()) for f in r]))
    ctx.clean(i)


@check("bad.invalid-ids", "§1 Reading (251, 252, 255 address nobody)",
       "ping, read and write to 251, 252, 255: no answer, nothing changes on any servo")
def bad_ids(ctx):
    before = {i: ctx.read(i, 0x12) for i in ctx.ids}
    for bad in spec.INVALID_IDS:
        ctx.silent(fr.ping(bad), "ping %d" % bad)
        ctx.silent(fr.read(bad, 0x0B), "read %d" % bad)
        ctx.silent(fr.write(bad, 0x12, spec.u16(222)), "write %d" % bad)
    for i in ctx.ids:
        expect(ctx.read(i, 0x12) == before[i], "servo %d: 0x12 changed" % i)
        expect(not ctx.status(i) & spec.BITS_56, "servo %d: status bits set" % i)


@check("decision:bad.read-extra-bytes", "decision: Malformed frames",
       "a read with two address bytes: bit 5 in a short response")
def bad_read_extra(ctx):
    i = ctx.ids[0]
    r = ctx.ask(fr.encode_command(i, 0x02, 0x0B, b"\x0C"))
    expect(r and r[0].is_status and r[0].status & spec.BITS_56 == spec.BIT_EXCEPTION,
           "answered %s" % [hexs(f.to_bytes()) for f in r])
    ctx.clean(i)


@check("decision:bad.ping-params", "decision: Malformed frames",
       "a ping with a parameter byte: still answered, with bit 5")
def bad_ping_params(ctx):
    i = ctx.ids[0]
    core = bytes([i, 3, 0x01, 0x00])
    r = ctx.ask(b"\xF9\xFF" + core + bytes([~sum(core) & 0xFF]))
    expect(r and r[0].is_status and r[0].status & spec.BITS_56 == spec.BIT_EXCEPTION,
           "answered %s" % [hexs(f.to_bytes()) for f in r])
    ctx.clean(i)


@check("decision:bad.write-no-address", "decision: Malformed frames",
       "a write without an address byte: no answer at level 0, bit 5 at the next ping")
def bad_write_noaddr(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x11])
    try:
        ctx.write_ok(i, 0x11, bytes([saved[0x11][0] & 0xF7]))
        core = bytes([i, 2, 0x03])
        ctx.silent(b"\xF9\xFF" + core + bytes([~sum(core) & 0xFF]))
        st = ctx.status(i)
        expect(st & spec.BITS_56 == spec.BIT_EXCEPTION, "ping 0x%02X" % st)
    finally:
        ctx.restore(i, saved)


# ---- wrong-length writes: bit 6, nothing changes (§4 Decision) -----------
def _wrong_lengths(reg):
    ok = set(reg.lengths)
    out = {0} | {n + 1 for n in ok} | {n - 1 for n in ok if n > 1}
    return sorted(n for n in out if n not in ok)


def _write_length(reg):
    def fn(ctx):
        i = ctx.ids[0]
        before = ctx.read(i, reg.addr) if reg.readable else None
        for n in _wrong_lengths(reg):
            value = (before * 2)[:n] if before else bytes(n)
            if reg.addr == 0x02:
                value = (spec.RESTART_MAGIC * 2)[:n]
            ctx.write_fails(i, reg.addr, value, spec.BIT_FAILED, "%d-byte " % n)
            if reg.readable:
                expect(ctx.read(i, reg.addr) == before, "a %d-byte write changed 0x%02X" % (n, reg.addr))
    return fn


for _r in spec.REGISTERS:
    if _r.writable:
        check("bad.write-length.0x%02X" % _r.addr, "§4 Decision (wrong length: bit 6)",
              "0x%02X %s written with %s bytes (it takes %s): bit 6, unchanged"
              % (_r.addr, _r.name, _wrong_lengths(_r), "/".join(map(str, _r.lengths))))(_write_length(_r))
