# SPDX-License-Identifier: Apache-2.0
"""The baud-rate commands of kmx: set-baud, scan --all-bauds and rescue.

They need a bus whose line rate the master can change: a serial port
(serial:DEV@BAUD) or the emulated bus over RFC 2217
(rfc2217:HOST:PORT@BAUD, sim/bus/servo-bus "Baud"); a raw tcp: bus carries
bytes at whatever rate the hub was started with and cannot follow a servo
to another baud, so these commands say so instead of failing later.

A baud change is stored at once (0x10 = baud / 100, docs/protocol.md §5.1) and
takes effect at the next restart (§3): set-baud writes it, restarts the
servo, switches the master and pings the servo at the new rate. scan
--all-bauds and rescue try the standard rates in turn with a super-ID ping
(§1: every servo answers, whatever its ID), so a servo is found when
neither its ID nor its baud is known."""

import time

from . import frame as fr
from .bus import BOOT_TIMEOUT
from .errors import KmxError, NoAnswer, RangeError
from .transport import BAUD_MAX, BAUD_MIN, parse_spec  # noqa: F401 (kmx.cli shows them)

# Tried in this order by scan --all-bauds and rescue: the fresh servo's
# 115200 first, then the common adapter rates, within the products' range.
FRESH_BAUD = 115200  # a fresh servo's (0x10 = 1152, §5.1)
STANDARD_BAUDS = (115200, 1000000, 500000, 250000, 230400, 57600, 38400, 19200, 9600)


def parse_baud(text):
    """A baud the servos can store: a whole number of hundreds in
    9600..1000000 (0x10 holds baud / 100). RangeError otherwise."""
    try:
        v = int(text, 10)
    except (TypeError, ValueError):
        raise RangeError("'%s' is not a baud rate: a whole number in %d..%d" % (text, BAUD_MIN, BAUD_MAX)) from None
    if not BAUD_MIN <= v <= BAUD_MAX:
        raise RangeError("%d baud is outside the servos' range %d..%d" % (v, BAUD_MIN, BAUD_MAX))
    if v % 100:
        raise RangeError("%d baud cannot be stored: 0x10 holds baud / 100, so a multiple of 100" % v)
    return v


def spec_at(spec, baud):
    """The bus spec string for the same port at another baud."""
    kind, _ = parse_spec(spec)
    if kind == "pty":
        return spec
    return spec.partition("@")[0] + "@%d" % baud


def _need_baud_control(bus, what):
    if not getattr(bus.transport, "can_set_baud", False):
        kind = parse_spec(bus.transport.spec)[0] if ":" in bus.transport.spec else "?"
        hint = ("use --bus rfc2217:HOST:PORT@BAUD: servo-bus takes RFC 2217 on the same port"
                if kind == "tcp" else "use a serial port: --bus serial:DEV@BAUD")
        raise KmxError("%s needs a bus whose baud kmx can change; %s cannot (%s)"
                       % (what, bus.transport.spec, hint))
    if parse_spec(bus.transport.spec)[0] == "pty":
        raise KmxError("%s: a pseudo-terminal has no line rate (%s); use a serial port or rfc2217:"
                       % (what, bus.transport.spec))


def _switch(bus, baud):
    bus.transport.set_baud(baud)
    time.sleep(0.02)  # let what was on the wire at the old rate arrive
    bus.transport.flush_input()


def _ping_until(bus, dev_id, seconds):
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        if bus.transact(fr.ping(dev_id), 1, min(0.05, bus.timeout)):
            return time.monotonic() - t0
    return None


def cmd_set_baud(bus, regs, args):
    new = args.baud
    _need_baud_control(bus, "set-baud")
    old = bus.baud
    bus.ping(args.id)  # it must be there at the bus's rate
    stored = int.from_bytes(bus.read(args.id, fr.REG_BAUD), "little") * 100
    if stored == new and old == new:
        print("ID %d already runs at %d baud" % (args.id, new))
        return 0
    bus.write(args.id, fr.REG_BAUD, (new // 100).to_bytes(2, "little"))
    status = bus.ping(args.id)
    if status & 0x60:  # §4 bit 6 refused (outside this product's range), bit 5 not supported
        raise KmxError("ID %d refused %d baud: status 0x%02X (%s)"
                       % (args.id, new, status, ", ".join(fr.status_words(status))))
    t0 = time.monotonic()
    bus.restart(args.id, wait=False)
    _switch(bus, new)
    boot = _ping_until(bus, args.id, BOOT_TIMEOUT)
    if boot is None:
        _switch(bus, old)
        back = _ping_until(bus, args.id, 0.5) is not None
        raise NoAnswer("ID %d: no answer at %d baud within %.1f s of the restart%s"
                       % (args.id, new, BOOT_TIMEOUT,
                          "; it still answers at %d (baud not changed)" % old if back
                          else "; not at %d either: try kmx rescue" % old))
    got = int.from_bytes(bus.read(args.id, fr.REG_BAUD), "little") * 100
    if got != new:
        raise KmxError("ID %d answers at %d baud but its 0x10 reads %d" % (args.id, new, got))
    print("ID %d: baud %d -> %d: answers at %d baud after a restart (%.0f ms); "
          "talk to it with --bus %s" % (args.id, old, new, new, 1000 * (time.monotonic() - t0),
                                         spec_at(bus.transport.spec, new)))
    return 0


def _scan_at(bus, regs, baud, scan_ms):
    """[(row, id)] of the servos answering a super-ID ping at this baud."""
    _switch(bus, baud)
    window = bus.scan_window() if scan_ms is None else scan_ms / 1000.0
    rows = []
    for dev_id, status in bus.scan(timeout=window):
        row = [dev_id, baud]
        for name in ("product_info", "firmware_version"):
            try:
                row.append(str(regs.get(dev_id, name)))
            except KmxError:
                row.append("?")
        row.append(", ".join(fr.status_words(status)))
        rows.append(row)
    return rows


def scan_all_bauds(bus, regs, scan_ms=None, bauds=STANDARD_BAUDS):
    """Rows [ID, baud, model, firmware, status] at every baud tried; the
    master is back at its own baud afterwards."""
    old = bus.baud
    rows = []
    try:
        for baud in bauds:
            rows += _scan_at(bus, regs, baud, scan_ms)
    finally:
        _switch(bus, old)
    return rows


def cmd_rescue(bus, regs, args):
    _need_baud_control(bus, "rescue")
    t0 = time.monotonic()
    rows = scan_all_bauds(bus, regs, args.scan_ms)
    tried = ", ".join(str(b) for b in STANDARD_BAUDS)
    if not rows:
        raise NoAnswer("no servo answered a super-ID ping at any of %s baud on %s (%.1f s): check "
                       "power and wiring; a servo at another baud answers only there"
                       % (tried, bus.transport.spec, time.monotonic() - t0))
    for dev_id, baud, model, firmware, status in rows:
        at = spec_at(bus.transport.spec, baud)
        print("found ID %d at %d baud (%s, firmware %s, %s)" % (dev_id, baud, model, firmware, status))
        print("  talk to it:      kmx --bus %s ping %d" % (at, dev_id))
        if baud != FRESH_BAUD:
            print("  back to 115200:  kmx --bus %s set-baud %d 115200" % (at, dev_id))
    ids = [r[0] for r in rows]
    if len(set(ids)) != len(ids):
        print("note: the same ID answers at two bauds: two servos share it; talk to each at its "
              "own baud and give one another ID (kmx set-id)")
    print("%d servo%s found over %d baud rates in %.1f s" % (
        len(rows), "" if len(rows) == 1 else "s", len(STANDARD_BAUDS), time.monotonic() - t0))
    return 0
