# SPDX-License-Identifier: Apache-2.0
"""§5 registers: answer types and lengths, read-only / write-only / reserved
outcomes, writes at and past the edges of each range the spec gives.
Defaults of a fresh servo are checked through the resets (checks_restart)."""
import spec
from ctx import check, expect, hexs
from wire import fr


def _reg_read(reg):
    def fn(ctx):
        for i in ctx.ids:
            f = ctx.read_frame(i, reg.addr)
            if reg.readable:
                expect(not f.is_status and f.cmd == 0x02 and f.addr == reg.addr,
                       "servo %d answered %s" % (i, hexs(f.to_bytes())))
                expect(len(f.params) in reg.lengths, "servo %d: %d value bytes, §5 says %s"
                       % (i, len(f.params), " or ".join(map(str, reg.lengths))))
                if reg.addr == 0x46 or reg.addr == 0x4C:
                    v = spec.to_int(f.params, True)
                    expect(len(f.params) == 2 or not -32768 <= v <= 32767,
                           "servo %d: %d answered as i32 though it fits an i16" % (i, v))
            else:
                expect(f.is_status and f.status & spec.BITS_56 == spec.BIT_EXCEPTION,
                       "read of write-only 0x%02X by servo %d answered %s, expected a short "
                       "response with bit 5" % (reg.addr, i, hexs(f.to_bytes())))
                ctx.clean(i)
    return fn


for _r in spec.REGISTERS:
    check("reg.0x%02X.read" % _r.addr, "§5, §4" if not _r.readable else "§5",
          ("0x%02X %s: a read answers %s value bytes" % (_r.addr, _r.name, "/".join(map(str, _r.lengths))))
          if _r.readable else
          ("0x%02X %s (write-only): a read answers bit 5 in a short response" % (_r.addr, _r.name))
          )(_reg_read(_r))


def _reg_write_ro(reg):
    def fn(ctx):
        i = ctx.ids[0]
        before = ctx.read(i, reg.addr)
        ctx.write_fails(i, reg.addr, bytes(len(before)) if before != bytes(len(before))
                        else b"\x01" * len(before), spec.BIT_EXCEPTION)
        if reg.addr in (0x0A, 0x0B, 0x0C, 0x16, 0x35):  # constant while we look
            expect(ctx.read(i, reg.addr) == before, "value changed by a refused write")
    return fn


for _r in spec.REGISTERS:
    if _r.access == "R" and _r.addr != 0x46:
        check("reg.0x%02X.write-read-only" % _r.addr, "§4, §5",
              "0x%02X %s is read-only: a write sets bit 5 and changes nothing" % (_r.addr, _r.name)
              )(_reg_write_ro(_r))


@check("reg.0x0B.value", "§5.1 0x0B", "protocol version is 0x05020000")
def reg_version(ctx):
    for i in ctx.ids:
        v = ctx.read_int(i, 0x0B)
        expect(v == spec.PROTOCOL_VERSION, "servo %d: 0x%08X" % (i, v))


@check("reg.0x0A.ascii", "§5.1 0x0A Decision", "product information is printable ASCII, 1..16 B")
def reg_product(ctx):
    for i in ctx.ids:
        v = ctx.read(i, 0x0A)
        expect(all(0x20 <= b < 0x7F for b in v), "servo %d: %s is not printable ASCII" % (i, hexs(v)))


@check("reg.0x01.random", "§5.1 0x01", "0x01 is [status][random]: the random byte varies")
def reg_random(ctx):
    i = ctx.ids[0]
    seen = {ctx.read(i, 0x01)[1] for _ in range(8)}
    expect(len(seen) > 1, "8 reads of 0x01 gave the same random byte %s" % seen)


@check("reg.reserved.read", "§5 reserve, §4 bit 5",
       "a read of every address not in the §5 map: short response with bit 5")
def reg_reserved_read(ctx):
    i = ctx.ids[0]
    bad = []
    for a in spec.RESERVED:
        r = ctx.ask(fr.read(i, a))
        if not (len(r) == 1 and r[0].is_status and r[0].status & spec.BITS_56 == spec.BIT_EXCEPTION):
            bad.append("0x%02X: %s" % (a, [hexs(f.to_bytes()) for f in r]))
    expect(not bad, "%d addresses: %s" % (len(bad), "; ".join(bad[:6])))
    ctx.clean(i)


@check("reg.reserved.write", "§5 reserve, §4 bit 5",
       "a 1-byte write to every address not in the §5 map: bit 5")
def reg_reserved_write(ctx):
    i = ctx.ids[0]
    bad = []
    for a in spec.RESERVED:
        st = ctx.write(i, a, b"\x00")
        if st & spec.BITS_56 != spec.BIT_EXCEPTION:
            bad.append("0x%02X: status 0x%02X" % (a, st))
            ctx.clean(i)
    expect(not bad, "%d addresses: %s" % (len(bad), "; ".join(bad[:6])))


# ---- ranges --------------------------------------------------------------
def _edges(addr, ok, bad, encode, restore_extra=()):
    """Values `ok` are accepted and read back; values `bad` set bit 6 and
    change nothing."""
    def fn(ctx):
        i = ctx.ids[0]
        saved = ctx.snapshot(i, list(restore_extra) + [addr])
        try:
            for v in ok:
                ctx.write_ok(i, addr, encode(v))
                got = ctx.read(i, addr)
                expect(got == encode(v), "0x%02X = %s read back %s" % (addr, hexs(encode(v)), hexs(got)))
            for v in bad:
                before = ctx.read(i, addr)
                ctx.write_fails(i, addr, encode(v), spec.BIT_FAILED)
                expect(ctx.read(i, addr) == before, "0x%02X changed by refused %s" % (addr, hexs(encode(v))))
        finally:
            ctx.restore(i, saved)
    return fn


RANGES = [
    # addr, ok, bad, encoder, also restore, basis
    (0x0F, [], [251, 252, 255], spec.u8, (), "§5.1 0x0F 0..250"),
    (0x12, [0, 65535, 200], [], spec.u16, (), "§5.1 0x12 u16"),
    (0x13, [0, 1000], [1001, 65535], spec.u16, (0x5B,), "§5.1 0x13 0..1000"),
    (0x17, [0, 10, -10], [], spec.i16, (), "§5.1 0x17 i16"),
    (0x32, [0x00, 0x0F], [], spec.u8, (), "§5.2 0x32 bits 0..3"),
    (0x33, [0x0F, 0x00], [], spec.u8, (), "§5.2 0x33 bits 0..3"),
    (0x34, [0x00, 0xD5, 0x89, 0x54], [0x20, 0x30, 0x02, 0x03], spec.u8, (),
     "§5.2 0x34 hold only for stall/current"),
    (0x3F, [(1000, 20), (0, 20), (600, 20)], [(1001, 20)],
     lambda v: spec.u16(v[0]) + spec.u8(v[1]), (), "§5.2 0x3F PWM 0..1000"),
    (0x5A, [1, 0], [3, 255], spec.u8, (), "§5.4 0x5A 0..2"),
    (0x5B, [0], [1001, 65535], spec.u16, (), "§5.4 0x5B 0..1000"),
    (0x64, [0, 1, 3], [4, 5, 255], spec.u8, (), "§5.4 0x64 0..3, 5 not writable"),
]
for _a, _ok, _bad, _enc, _extra, _basis in RANGES:
    check("reg.0x%02X.range" % _a, _basis,
          "0x%02X: %s accepted, %s refused with bit 6" % (_a, _ok or "-", _bad or "-")
          )(_edges(_a, _ok, _bad, _enc, _extra))


@check("reg.0x18.range", "§5.1 0x18 -100..100",
       "0x18 +100 and -100 add to 0x17; 101 and -101 set bit 6")
def reg_0x18(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x17])
    try:
        ctx.write_ok(i, 0x17, spec.i16(0))
        ctx.write_ok(i, 0x18, spec.u8(100))
        expect(ctx.read_int(i, 0x17) == 100, "0x17 = %d after +100" % ctx.read_int(i, 0x17))
        ctx.write_ok(i, 0x18, spec.u8(-100))
        expect(ctx.read_int(i, 0x17) == 0, "0x17 = %d after -100" % ctx.read_int(i, 0x17))
        for v in (101, -101, 127, -128):
            ctx.write_fails(i, 0x18, spec.u8(v), spec.BIT_FAILED)
            expect(ctx.read_int(i, 0x17) == 0, "0x17 changed by refused 0x18 = %d" % v)
    finally:
        ctx.restore(i, saved)


@check("reg.0x5B.follows-0x13", "§5.4 0x5B =0x13", "0x5B follows 0x13 when 0x13 is written")
def reg_follow_13(ctx):
    _follow(ctx, 0x13, 0x5B)


@check("reg.0x5C.follows-0x14", "§5.4 0x5C =0x14", "0x5C follows 0x14 when 0x14 is written")
def reg_follow_14(ctx):
    _follow(ctx, 0x14, 0x5C)


@check("reg.0x5D.follows-0x15", "§5.4 0x5D =0x15", "0x5D follows 0x15 when 0x15 is written")
def reg_follow_15(ctx):
    _follow(ctx, 0x15, 0x5D)


def _follow(ctx, maxreg, live):
    for i in ctx.ids[:1]:
        saved = ctx.snapshot(i, [maxreg, live])
        try:
            m = spec.to_int(saved[maxreg])
            expect(m > 1, "0x%02X is %d: nothing to lower" % (maxreg, m))
            ctx.write_ok(i, maxreg, spec.u16(m - 1))
            expect(ctx.read_int(i, live) == m - 1, "0x%02X = %d after 0x%02X = %d"
                   % (live, ctx.read_int(i, live), maxreg, m - 1))
            ctx.write_ok(i, maxreg, spec.u16(m))
            expect(ctx.read_int(i, live) == m, "0x%02X = %d after 0x%02X = %d"
                   % (live, ctx.read_int(i, live), maxreg, m))
        finally:
            ctx.restore(i, saved)


@check("decision:reg.limits-contradict", "decision: Register rules (limits that contradict)",
       "0x5B above 0x13, and angle limits with min >= max, set bit 6 and change nothing")
def reg_contradict(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x13, 0x5B, 0x19, 0x1A])
    try:
        ctx.write_ok(i, 0x13, spec.u16(500))
        ctx.write_fails(i, 0x5B, spec.u16(501), spec.BIT_FAILED)
        ctx.write_ok(i, 0x5B, spec.u16(500))
        ctx.write_ok(i, 0x19, spec.i16(0))
        ctx.write_ok(i, 0x1A, spec.i16(100))
        ctx.write_ok(i, 0x19, spec.i16(-100))
        ctx.write_fails(i, 0x19, spec.i16(100), spec.BIT_FAILED)
        ctx.write_fails(i, 0x1A, spec.i16(-100), spec.BIT_FAILED)
        expect(ctx.read_int(i, 0x19) == -100 and ctx.read_int(i, 0x1A) == 100, "limits changed")
    finally:
        ctx.restore(i, saved)


@check("decision:reg.reserved-bits", "decision: Register rules (reserved bits)",
       "0x32 written with bits 4..7 set: accepted, reads back the bits 0..3 only")
def reg_reserved_bits(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x32])
    try:
        ctx.write_ok(i, 0x32, b"\xF5")
        expect(ctx.read(i, 0x32) == b"\x05", "0x32 reads %s" % hexs(ctx.read(i, 0x32)))
    finally:
        ctx.restore(i, saved)


@check("reg.0x10.zero", "§1, §5.1 0x10 (baud = value x 100)",
       "0x10 = 0 (no baud) sets bit 6 and changes nothing")
def reg_baud_zero(ctx):
    _edges(0x10, [], [0], spec.u16)(ctx)


@check("reg.thresholds.write-back", "§5.2 0x3C..0x3E",
       "0x3C, 0x3D and 0x3E written with the values they read: accepted, unchanged")
def reg_thresholds(ctx):
    i = ctx.ids[0]
    for a in (0x3C, 0x3D, 0x3E, 0x14, 0x15, 0x19, 0x1A):
        v = ctx.read(i, a)
        ctx.write_ok(i, a, v)
        expect(ctx.read(i, a) == v, "0x%02X changed" % a)


@check("reg.0x3D.hysteresis", "§5.2 0x3D", "0x3D (70, 10) accepted and read back")
def reg_0x3d(ctx):
    _edges(0x3D, [(70, 10), (60, 5)], [], lambda v: bytes(v))(ctx)


@check("reg.motion.values", "§5.4 0x65..0x70, §4 bit 6",
       "out-of-range motion values set bit 6: 0x6E +/-1001, 0x67 low nibble 3, 0x70 bit 6, "
       "0x66 of 3 bytes")
def reg_motion_values(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x64, 0x5A])
    try:
        ctx.write_fails(i, 0x6E, spec.i16(1001), spec.BIT_FAILED)
        ctx.write_fails(i, 0x6E, spec.i16(-1001), spec.BIT_FAILED)
        ctx.write_fails(i, 0x67, bytes([0x03]) + spec.i16(0) + spec.i16(0), spec.BIT_FAILED)
        ctx.write_fails(i, 0x67, bytes([0x20]) + spec.i16(0) + spec.i16(0), spec.BIT_FAILED)
        ctx.write_fails(i, 0x70, bytes([0x40]) + spec.u16(0) + spec.u16(0), spec.BIT_FAILED)
        ctx.write_fails(i, 0x66, b"\x00\x00\x00", spec.BIT_FAILED)
        ctx.write_ok(i, 0x6E, spec.i16(0))          # 0 = stop: accepted
        ctx.write_ok(i, 0x70, bytes([0x80]) + spec.u16(0) + spec.u16(0))  # stop now
    finally:
        ctx.restore(i, saved)


@check("reg.motion.torque-off", "§5.4 (rotation commands run only with 0x64 = 2 or 3)",
       "with 0x64 = 0 a 0x65 move is refused: bit 6, 0x64 stays 0")
def reg_torque_off(ctx):
    i = ctx.ids[0]
    saved = ctx.snapshot(i, [0x64])
    try:
        ctx.write_ok(i, 0x64, b"\x00")
        pos = ctx.read_int(i, 0x46)
        ctx.write_fails(i, 0x65, spec.i16(max(-1000, min(1000, pos + 50))) + spec.u16(200), spec.BIT_FAILED)
        expect(ctx.read_int(i, 0x64) == 0, "0x64 changed")
    finally:
        ctx.restore(i, saved)
