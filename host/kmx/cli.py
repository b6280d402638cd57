# SPDX-License-Identifier: Apache-2.0
"""The `kmx` command: find servos on a bus and read and set their registers
by name, with units (names, units and ranges from docs/registers.json).

  kmx [--bus SPEC] scan [--all-bauds]   every servo: ID, baud, model, firmware, status
  kmx [--bus SPEC] ping ID
  kmx [--bus SPEC] get ID NAME...       e.g. kmx get 1 position voltage
  kmx [--bus SPEC] set ID NAME VALUE... e.g. kmx set 1 move_time 45 500
  kmx [--bus SPEC] dump ID              every register, decoded
  kmx [--bus SPEC] torque ID on|off|brake
  kmx [--bus SPEC] move ID ANGLE [--time MS | --speed DPS] [--wait]
  kmx [--bus SPEC] monitor ID... [--interval MS] [--count N] [--csv]
  kmx [--bus SPEC] set-id ID NEW        write the ID, restart, find it at NEW
  kmx [--bus SPEC] set-baud ID BAUD     write the baud, restart, find it at BAUD
  kmx [--bus SPEC] rescue               find servos of unknown ID and baud, say how to reach them
  kmx [--bus SPEC] fault-log ID         the last protection and self-test events
  kmx [--bus SPEC] plot ID --out F.png [--seconds S] [--step ANGLE [--time MS | --speed DPS]]
  kmx [--bus SPEC] update --ids 1,2,3 IMAGE.kmfw   firmware update (0x78), checked first
  kmx [--bus SPEC] update --rescue IMAGE.kmfw      one servo alone on the bus, any ID
  kmx [--bus SPEC] trace [--move]       a session with every frame printed and decoded
  kmx [--bus SPEC] web [--port N]       the servo wizard: a page on http://127.0.0.1:8765/

SPEC: tcp:HOST:PORT (sim/bus/servo-bus, host-sim), a device path
/dev/ttyUSB0[@BAUD] (or serial:/dev/ttyUSB0@115200, pty:/dev/pts/N),
rfc2217:HOST:PORT@BAUD (sim/bus/servo-bus as a serial port whose baud kmx can
change: set-baud, scan --all-bauds, rescue), or any pyserial URL:
socket://HOST:PORT, rfc2217://HOST:PORT[@BAUD], loop://, spy://DEVICE (a hex
trace of every byte), hwgrep://REGEXP (an adapter by its description);
default $KMX_BUS, else tcp:127.0.0.1:7000. Failures print one line `kmx: ...` and
exit 1 (2 for a bad command line), Ctrl-C one line `kmx: interrupted` and
exit 130, never a traceback.

One servo per ID: a write that changes an ID (set ID id N, set-id, set ID
userdata_reset 2) is refused when another servo answers on the new ID or
two servos share the old one; scan warns about an ID two servos answer on
(docs/protocol.md §5.1 0x01's random byte) and prints the command that separates
them once one of them is alone on the bus.
"""

import argparse
import os
import signal
import sys
import threading
import time

from . import baud as kbaud
from . import faultlog
from . import frame as fr
from . import plot
from . import session as ksession
from . import update as kupdate
from .bus import Bus
from .errors import InUpdateMode, KmxError, NoAnswer, RegisterError
from .registers import RegisterMap, Registers

DEFAULT_BUS = "tcp:127.0.0.1:7000"


def servo_id(text):
    try:
        v = int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError("'%s' is not a servo ID (0..%d)" % (text, fr.ID_MAX)) from None
    if not 0 <= v <= fr.ID_MAX:
        raise argparse.ArgumentTypeError("servo ID %d is outside 0..%d" % (v, fr.ID_MAX))
    return v


def _positive(what):
    def parse(text):
        try:
            v = float(text)
        except ValueError:
            v = float("nan")
        if not v > 0 or v == float("inf"):
            raise argparse.ArgumentTypeError("'%s' is not a positive number of %s" % (text, what))
        return v
    return parse


positive_ms = _positive("milliseconds")
positive_s = _positive("seconds")


def baud_arg(text):
    try:
        return kbaud.parse_baud(text)
    except KmxError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def count(text):
    try:
        v = int(text)
    except ValueError:
        v = 0
    if v < 1:
        raise argparse.ArgumentTypeError("'%s' is not a count of 1 or more" % text)
    return v


def _table(rows, header):
    widths = [max(len(str(r[i])) for r in rows + [header]) for i in range(len(header))]
    fmt = "  ".join("%%-%ds" % w for w in widths)
    return "\n".join((fmt % tuple(r)).rstrip() for r in [header] + rows)


def cmd_scan(bus, regs, args):
    t0 = time.monotonic()
    if args.all_bauds:
        kbaud._need_baud_control(bus, "scan --all-bauds")
        rows = kbaud.scan_all_bauds(bus, regs, args.scan_ms)
        if not rows:
            raise NoAnswer("no servo answered a super-ID ping at any of %s baud on %s"
                           % (", ".join(map(str, kbaud.STANDARD_BAUDS)), bus.transport.spec))
        print(_table(rows, ["ID", "baud", "model", "firmware", "status"]))
        print("%d servo%s on %s at %d baud rates (super-ID scans, %.1f s)" % (
            len(rows), "" if len(rows) == 1 else "s", bus.transport.spec, len(kbaud.STANDARD_BAUDS),
            time.monotonic() - t0))
        return 0
    window = bus.scan_window() if args.scan_ms is None else args.scan_ms / 1000.0
    found = bus.scan(timeout=window)
    if not found:
        raise NoAnswer("no servo answered the super-ID ping within %.0f ms on %s (a servo in update mode "
                       "does not answer it: `kmx ping ID` names one, `kmx update --rescue` reaches one alone)"
                       % (1000 * window, bus.transport.spec))
    rows = []
    for dev_id, status in found:
        row = [dev_id]
        for name in ("baud", "product_info", "firmware_version"):
            try:
                row.append(str(regs.get(dev_id, name)).replace(" baud", ""))
            except KmxError:
                row.append("?")
        row.append(", ".join(fr.status_words(status)))
        rows.append(row)
    print(_table(rows, ["ID", "baud", "model", "firmware", "status"]))
    shared = bus.shared_ids(found)
    order = [i for i, _ in found]
    note = "" if order == sorted(order) else " (answers out of ID order: %s)" % order
    print("%d servo%s on %s (super-ID scan, %.0f ms)%s" % (
        len(found), "" if len(found) == 1 else "s", bus.transport.spec, 1000 * (time.monotonic() - t0), note))
    for dev_id, how in sorted(shared.items()):
        print(_shared_warning(bus, dev_id, how, order))
    return 0


def _shared_warning(bus, dev_id, how, taken):
    """What to do about two servos on one ID. No frame addresses one of
    them alone (every frame to the ID reaches both, docs/protocol.md §1), so the
    way apart is physical: one of them alone on the bus gets another ID."""
    free = next(i for i in range(1, fr.ID_MAX + 1) if i not in taken)
    return ("warning: ID %d gave %s: two servos share ID %d. No command reaches one of them alone "
            "(every frame to ID %d reaches both), so: disconnect all but one of the servos on ID %d, run\n"
            "  kmx --bus %s set-id %d %d\n"
            "then reconnect the others (repeat while ID %d answers twice)."
            % (dev_id, how, dev_id, dev_id, dev_id, bus.transport.spec, dev_id, free, dev_id))


def cmd_ping(bus, regs, args):
    t0 = time.monotonic()
    status = bus.ping(args.id)
    print("ID %d: status 0x%02X (%s), answered in %.1f ms" % (
        args.id, status, ", ".join(fr.status_words(status)), 1000 * (time.monotonic() - t0)))
    try:
        bus.check_update_mode(args.id)
    except InUpdateMode as e:
        print(str(e))
    return 0


def _shown(reg, value, raw):
    text = "%s (0x%02X) = %s" % (reg.name, reg.address, value)
    return text + ("  [%s]" % raw.hex(" ").upper() if raw is not None else "")


def cmd_get(bus, regs, args):
    for name in args.names:
        reg = regs.map.find(name)
        if not reg.readable:
            raise RegisterError("%s (0x%02X) is write-only" % (reg.name, reg.address))
        data = bus.read(args.id, reg.address)
        print(_shown(reg, reg.decode(data), data if args.raw else None))
    return 0


def cmd_set(bus, regs, args):
    reg = regs.map.find(args.name)
    data = reg.encode(args.value if len(args.value) > 1 else args.value[0])
    regs.check(args.id, reg, data)
    bus.write(args.id, reg.address, data)
    # §3: the new ID applies right after the write (a 0x03 level-2 reset's ID
    # 0 too, docs/protocol-decisions.md); §4: bit 6 = the write was refused,
    # bit 5 = not supported
    now_id = args.id
    if reg.address == fr.REG_ID:
        now_id = data[0]
    elif reg.address == fr.REG_USERDATA_RESET and data == b"\x02":
        now_id = 0
    try:
        status = bus.ping(now_id)
    except NoAnswer:
        if now_id != args.id:
            raise NoAnswer("wrote %s = %s to ID %d, but nothing answers at ID %d"
                           % (reg.name, " ".join(args.value), args.id, now_id)) from None
        raise
    if status & 0x20:
        bus.check_update_mode(now_id)  # a bootloader supports no register write
    if status & 0x60:
        raise KmxError("ID %d refused %s (0x%02X) = %s: status 0x%02X (%s)" % (
            args.id, reg.name, reg.address, " ".join(args.value), status, ", ".join(fr.status_words(status))))
    if reg.readable:
        got = bus.read(now_id, reg.address)
        print(_shown(reg, reg.decode(got), got if args.raw else None) +
              ("  (takes effect after restart)" if reg.address == fr.REG_BAUD else "") +
              ("  (the servo answers at ID %d now)" % now_id if reg.address == fr.REG_ID else ""))
    else:
        print("%s (0x%02X) <- %s  [%s]" % (reg.name, reg.address, reg.decode(data) if reg.layout != "magic"
                                           else data.hex(" ").upper(), data.hex(" ").upper()) +
              ("  (the servo answers at ID %d now)" % now_id if now_id != args.id else ""))
    return 0


def cmd_dump(bus, regs, args):
    rows = []
    for reg in regs.map:
        if not reg.readable:
            rows.append(["0x%02X" % reg.address, reg.name, "(write-only)", reg.title])
            continue
        data = bus.read(args.id, reg.address)
        value = str(reg.decode(data))
        if args.raw:
            value += "  [%s]" % data.hex(" ").upper()
        rows.append(["0x%02X" % reg.address, reg.name, value, reg.title])
    print(_table(rows, ["adr", "name", "value", "meaning"]))
    return 0


TORQUE = {"off": 0, "brake": 1, "on": 2}  # §5.4 0x64
TORQUE_WORDS = {0: "off, free", 1: "off, brake damping", 2: "on, holding", 3: "armed: on at the next move",
                5: "off after a protection"}


def _write_checked(bus, dev_id, reg, data, what):
    """Writes and pings: §4 bit 6 (refused) or bit 5 (not supported) -> KmxError."""
    bus.write(dev_id, reg.address, data)
    status = bus.ping(dev_id)
    if status & 0x20:
        bus.check_update_mode(dev_id)  # a bootloader supports no register write
    if status & 0x60:
        raise KmxError("ID %d refused %s: status 0x%02X (%s)" % (
            dev_id, what, status, ", ".join(fr.status_words(status))))
    return status


def cmd_torque(bus, regs, args):
    reg = regs.map.find("torque_switch")
    _write_checked(bus, args.id, reg, bytes([TORQUE[args.state]]), "torque %s" % args.state)
    v = bus.read(args.id, reg.address)[0]
    print("ID %d: torque_switch (0x64) = %d (%s)" % (args.id, v, TORQUE_WORDS.get(v, "?")))
    return 0


def cmd_move(bus, regs, args):
    if args.speed is not None:
        reg = regs.map.find("move_speed")
        data = reg.encode([args.angle, args.speed])
    elif args.time is not None:
        reg = regs.map.find("move_time")
        data = reg.encode([args.angle, args.time])
    else:
        reg = regs.map.find("move_time")  # §5.4: time omitted = fastest
        data = reg.encode([args.angle])
    regs.check(args.id, reg, data)
    t0 = time.monotonic()
    _write_checked(bus, args.id, reg, data, "%s = %s" % (reg.name, reg.decode(data)))
    if not args.wait:
        print("ID %d: %s <- %s" % (args.id, reg.name, reg.decode(data)))
        return 0
    pos = regs.map.find("position")
    deadline = t0 + args.wait_s
    while True:
        running = bus.read(args.id, fr.REG_STATUS)[0] & 0x80  # §4 bit 7: executing a rotation command
        if not running:
            break
        if time.monotonic() > deadline:
            raise KmxError("ID %d: still moving after %.1f s (at %s)" % (
                args.id, args.wait_s, pos.decode(bus.read(args.id, pos.address))))
        time.sleep(0.02)
    print("ID %d: %s <- %s; stopped at %s after %.0f ms" % (
        args.id, reg.name, reg.decode(data), pos.decode(bus.read(args.id, pos.address)),
        1000 * (time.monotonic() - t0)))
    return 0


MONITOR = ("position", "speed", "current", "temperature", "voltage")


def monitor_sample(bus, regs, names, ids):
    """One sample of registers `names` of every servo in ids: one multi-ID
    read (0x82) per register for all of them; a servo missing from one is
    read on its own (0x02), and by 0x02 only in later samples of this regs
    (Registers.read_each: a servo without 0x82 reports its status bit 5
    once, not on every sample). {id: [Value per name]}."""
    out = {i: [] for i in ids}
    for name in names:
        got = regs.read_each(ids, name)
        for i in ids:
            out[i].append(got[i])
    return out


def _monitor_rows(args, regs_shown, sample, t):
    """The rows of one sample: CSV lines, or table rows."""
    rows = []
    for dev_id in args.ids:
        *values, status = sample[dev_id]
        code = status.raw[0]
        if args.csv:
            words = " ".join(w.replace(" ", "-") for w in fr.status_words(code))
            rows.append(",".join(["%.3f" % t, str(dev_id)] + ["%.*f" % (r.decimals(), v.value)
                                                             for r, v in zip(regs_shown, values)] + [words]))
        else:
            rows.append([dev_id] + [str(v) for v in values] + [", ".join(fr.status_words(code))])
    return rows


def cmd_monitor(bus, regs, args):
    """Samples on a fixed schedule (t0 + n x interval, so the interval is
    the real sample period), each sample by 0x82 reads; a sample that takes
    longer than the interval is said in the table (the next one starts at once)."""
    regs_shown = [regs.map.find(n) for n in MONITOR]
    header = ["t_s", "id"] + ["%s_%s" % (r.name, r.unit().replace("°/s", "dps").replace("°C", "c")
                                         .replace("°", "deg").lower()) for r in regs_shown] + ["status"]
    live = not args.csv and sys.stdout.isatty()
    if args.csv:
        print(",".join(header), flush=True)
    period = args.interval / 1000.0
    t0 = time.monotonic()
    n = 0
    try:
        while args.count is None or n < args.count:
            t = time.monotonic() - t0
            sample = monitor_sample(bus, regs, MONITOR + ("status",), args.ids)
            took = time.monotonic() - t0 - t
            rows = _monitor_rows(args, regs_shown, sample, t)
            if args.csv:
                print("\n".join(rows), flush=True)
            else:
                late = "" if took <= period else "; a sample takes %.0f ms, longer than --interval" % (1000 * took)
                print(("\033[H\033[J" if live else "") + "t = %.2f s (sample every %.0f ms, 0x82%s)\n%s"
                      % (t, args.interval, late, _table(rows, ["ID"] + list(MONITOR) + ["status"])), flush=True)
            n += 1
            if args.count is None or n < args.count:
                time.sleep(max(0.0, t0 + n * period - time.monotonic()))
    except KeyboardInterrupt:
        pass  # the normal way out of a live monitor
    return 0


def cmd_set_id(bus, regs, args):
    if args.new == args.id:
        raise KmxError("ID %d already is %d" % (args.id, args.new))
    bus.ping(args.id)  # it must be there
    bus.write(args.id, fr.REG_ID, bytes([args.new]))  # refused (IdTaken) if NEW is taken or ID shared
    bus.ping(args.new)  # §3: the new ID applies right after the write
    boot = bus.restart(args.new)  # and is stored: it survives the restart
    print("ID %d -> %d: answers at ID %d after a restart (%.0f ms)" % (args.id, args.new, args.new, 1000 * boot))
    return 0


def cmd_fault_log(bus, regs, args):
    events, held, kept = faultlog.read_summary(bus, args.id)
    source, cause = faultlog.read_boot(bus, args.id)
    print("ID %d: %d event%s recorded, %d held (%d from before the last reset); last reset: %s; "
          "user data: %s" % (args.id, events, "" if events == 1 else "s", held, kept, cause, source))
    entries = faultlog.read_entries(bus, args.id, held)
    if entries:
        print(_table([e.row(i) for i, e in enumerate(entries)], faultlog.ROW_HEADER))
    else:
        print("no entries")
    return 0


def cmd_plot(bus, regs, args):
    target = None
    t0 = time.monotonic()
    if args.step is not None:
        if args.speed is not None:
            reg, vals = regs.map.find("move_speed"), [args.step, args.speed]
        else:
            reg, vals = regs.map.find("move_time"), [args.step] + ([args.time] if args.time is not None else [])
        data = reg.encode(vals)
        regs.check(args.id, reg, data)
        t0 = time.monotonic()
        _write_checked(bus, args.id, reg, data, "%s = %s" % (reg.name, reg.decode(data)))
        target = reg.decode(data).value
    trace = plot.record(bus, regs, args.id, args.seconds, args.interval / 1000.0, t0, target)
    title = "ID %d: %s" % (args.id, "step to %.1f °" % target if target is not None else "trace")
    plot.render(trace, args.out, title)
    line = "wrote %s: %d samples of position, speed, current over %.1f s" % (args.out, len(trace), args.seconds)
    if target is not None:
        at = trace.settled_at()
        line += "; %s" % ("within %.1f ° of %.1f ° from %.0f ms" % (plot.SETTLE_DEG, target, 1000 * at)
                          if at is not None else "did not settle at %.1f °" % target)
    print(line)
    return 0


def trace_to_stderr(direction, item):
    """--trace: every frame on stderr, answers decoded as kmx trace prints them."""
    print(ksession.trace_line(direction, item), file=sys.stderr)


def cmd_update(args):
    """kmx update: servo-update's checks and pass (kmx/update.py) on kmx's bus."""
    args.prog = "kmx"
    me = sys.argv[0] if not sys.argv[0].endswith("__main__.py") else "kmx"
    args.finish_argv = [me, "--bus", args.bus, "update"]
    args.trace = trace_to_stderr if args.trace else None
    try:
        kupdate.check_args(args)
    except kupdate.Refused as e:
        print("kmx: %s" % e.args[0], file=sys.stderr)
        return e.args[1]
    return kupdate.run(args)


def cmd_web(args):
    """kmx web: the wizard page (kmx/web.py)."""
    from . import web
    return web.cmd_web(args)


def cmd_trace(args):
    """kmx trace: the readable session of kmx/session.py (servo-session's)."""
    ksession.load_registers()
    ksession.run(ksession.Session(args.bus), args.move)
    return 0


def build_parser():
    ap = argparse.ArgumentParser(prog="kmx", description=__doc__.split("\n\n")[0],
                                 epilog=__doc__.split("\n\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bus", default=os.environ.get("KMX_BUS", DEFAULT_BUS),
                    help="the bus: tcp:HOST:PORT, a device path /dev/ttyUSB0[@BAUD], rfc2217:HOST:PORT@BAUD, "
                         "or a pyserial URL socket://, rfc2217://, loop://, spy://, hwgrep:// "
                         "(default $KMX_BUS or %s)"
                    % DEFAULT_BUS)
    ap.add_argument("--timeout", type=positive_ms, default=100, metavar="MS",
                    help="wait for one answer, ms (default 100)")
    ap.add_argument("--retries", type=int, default=2, choices=range(0, 10), metavar="N",
                    help="extra tries of a read or ping (default 2)")
    ap.add_argument("--trace", action="store_true", help="print every frame sent and received (stderr)")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser("scan", help="find every servo (super-ID ping) with its baud, model, firmware, status",
                       description="Pings the super ID (0xFD): every servo answers in its own slot, in ID "
                                   "order; then reads each one's baud, model and firmware, and reads 0x01 "
                                   "with the super ID: an ID that answers twice (two random bytes), or "
                                   "whose answers collide, is shared by two servos, and a warning says how "
                                   "to separate them.")
    p.add_argument("--scan-ms", type=positive_ms, metavar="MS",
                   help="listen this long for answers (default: until ID 250's slot has passed at the "
                        "bus baud, 270 ms at 115200)")
    p.add_argument("--all-bauds", action="store_true",
                   help="scan at every standard baud (%s) in turn; the ID and baud columns say "
                        "where each servo answered (needs a serial or rfc2217: bus)"
                        % ", ".join(map(str, kbaud.STANDARD_BAUDS)))
    p.set_defaults(run=cmd_scan)

    p = sub.add_parser("ping", help="ping one servo: its status in words",
                       description="Pings one servo (0x01) and prints its status byte in words.")
    p.add_argument("id", type=servo_id, help="servo ID, 0..250")
    p.set_defaults(run=cmd_ping)

    p = sub.add_parser("get", help="read registers by name or address, with units",
                       description="Reads registers by name (e.g. position, voltage) or address "
                                   "(0x46), decoded with units. `kmx dump` lists the names.")
    p.add_argument("id", type=servo_id, help="servo ID, 0..250")
    p.add_argument("names", nargs="+", metavar="NAME", help="register name or address")
    p.add_argument("--raw", action="store_true", help="also print the wire bytes")
    p.set_defaults(run=cmd_get)

    p = sub.add_parser("set", help="write a register by name, value in its units",
                       description="Writes a register by name or address. The value is in the "
                                   "register's units (position 45.0 = 45.0 degrees, voltage in V); "
                                   "two-field registers take two values (move_time 45 500 = 45.0 "
                                   "degrees in 500 ms). The value is checked against the register's "
                                   "type and range before anything is sent, the servo's status is "
                                   "checked after, and the register is read back when it can be.")
    p.add_argument("id", type=servo_id, help="servo ID, 0..250")
    p.add_argument("name", metavar="NAME", help="register name or address")
    p.add_argument("value", nargs="+", metavar="VALUE", help="value(s) in the register's units")
    p.add_argument("--raw", action="store_true", help="also print the wire bytes")
    p.set_defaults(run=cmd_set)

    p = sub.add_parser("dump", help="every register of one servo, named, decoded, with units",
                       description="Reads every readable register of one servo and prints it decoded "
                                   "with units; write-only registers are listed as such.")
    p.add_argument("id", type=servo_id, help="servo ID, 0..250")
    p.add_argument("--raw", action="store_true", help="also print the wire bytes")
    p.set_defaults(run=cmd_dump)

    p = sub.add_parser("torque", help="torque on (hold), off (free) or brake",
                       description="Writes the torque switch 0x64: on = 2 (hold the current position), "
                                   "off = 0 (free), brake = 1 (off with brake damping); reads it back.")
    p.add_argument("id", type=servo_id, help="servo ID, 0..250")
    p.add_argument("state", choices=sorted(TORQUE), help="on, off or brake")
    p.set_defaults(run=cmd_torque)

    p = sub.add_parser("move", help="move to an angle (degrees), in a time or at a speed",
                       description="Moves to ANGLE degrees: 0x65 with --time MS, 0x66 with --speed "
                                   "DPS, else 0x65 without a time (as fast as allowed). The torque "
                                   "switch must be on or armed (kmx torque ID on). --wait polls the "
                                   "status until the move ends and prints where it stopped.")
    p.add_argument("id", type=servo_id, help="servo ID, 0..250")
    p.add_argument("angle", type=float, help="target, degrees (0.1 ° steps)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--time", type=float, metavar="MS", help="take this long, ms")
    g.add_argument("--speed", type=float, metavar="DPS", help="at this speed, °/s")
    p.add_argument("--wait", action="store_true", help="wait until the move ends")
    p.add_argument("--wait-s", type=positive_s, default=10.0, metavar="S", help="give up waiting after S s (default 10)")
    p.set_defaults(run=cmd_move)

    p = sub.add_parser("monitor", help="live table of position, speed, current, temperature, voltage, status",
                       description="Reads position, speed, current, temperature, voltage and status of "
                                   "each servo every --interval ms and prints them as a refreshing "
                                   "table (a terminal), one table per sample (a pipe), or CSV rows "
                                   "(--csv, values in the units of the header). Ctrl-C stops it.")
    p.add_argument("ids", type=servo_id, nargs="+", metavar="ID", help="servo IDs")
    p.add_argument("--interval", type=positive_ms, default=200, metavar="MS", help="sample period (default 200)")
    p.add_argument("--count", type=count, metavar="N", help="stop after N samples (default: until Ctrl-C)")
    p.add_argument("--csv", action="store_true", help="CSV rows instead of a table")
    p.set_defaults(run=cmd_monitor)

    p = sub.add_parser("set-id", help="change a servo's ID, restart it and find it at the new ID",
                       description="Checks that NEW is free and that one servo only answers on ID, "
                                   "writes the ID register 0x0F, restarts the servo and pings it at NEW: "
                                   "the ID is stored user data.")
    p.add_argument("id", type=servo_id, help="the servo's ID now")
    p.add_argument("new", type=servo_id, help="its new ID, 0..250")
    p.set_defaults(run=cmd_set_id)

    p = sub.add_parser("set-baud", help="change a servo's baud, restart it and find it at the new baud",
                       description="Writes the baud register 0x10 (baud / 100), restarts the servo, "
                                   "switches the master to BAUD and pings the servo there; on failure "
                                   "it switches back and says whether the servo still answers at the "
                                   "old baud. Needs a bus whose baud kmx can change: serial:DEV@BAUD or "
                                   "rfc2217:HOST:PORT@BAUD (sim/bus/servo-bus).")
    p.add_argument("id", type=servo_id, help="the servo's ID")
    p.add_argument("baud", type=baud_arg, help="its new baud, %d..%d, a multiple of 100"
                   % (kbaud.BAUD_MIN, kbaud.BAUD_MAX))
    p.set_defaults(run=kbaud.cmd_set_baud)

    p = sub.add_parser("rescue", help="find servos whose ID or baud is unknown; print how to reach them",
                       description="Pings the super ID at every standard baud (%s): every servo answers "
                                   "whatever its ID. Prints each one found with its ID and baud and the "
                                   "kmx command lines that reach it and bring it back to 115200. Needs a "
                                   "serial or rfc2217: bus." % ", ".join(map(str, kbaud.STANDARD_BAUDS)))
    p.add_argument("--scan-ms", type=positive_ms, metavar="MS",
                   help="listen this long at each baud (default: until ID 250's slot has passed)")
    p.set_defaults(run=kbaud.cmd_rescue)

    p = sub.add_parser("fault-log", help="the last protection and self-test events, newest first",
                       description="Reads the fault log of one servo (our extension command 0x7F, "
                                   "docs/protocol-decisions.md): each protection trip and release and "
                                   "each self-test finding, newest first, with the supply, current, "
                                   "temperature and position at that moment; plus why the servo last "
                                   "reset and where its user data came from.")
    p.add_argument("id", type=servo_id, help="servo ID, 0..250")
    p.set_defaults(run=cmd_fault_log)

    p = sub.add_parser("plot", help="a trace or a step response to a PNG (python3-matplotlib)",
                       description="Samples position, speed and current of one servo every --interval "
                                   "ms for --seconds and draws them to a PNG. With --step ANGLE it "
                                   "first commands a move (0x65, or 0x66 with --speed; the torque "
                                   "switch must be on or armed) and draws the step response with its "
                                   "target. Needs Debian's python3-matplotlib.")
    p.add_argument("id", type=servo_id, help="servo ID, 0..250")
    p.add_argument("--out", required=True, metavar="FILE.png", help="the picture to write")
    p.add_argument("--seconds", type=positive_s, default=2.0, metavar="S", help="record this long (default 2)")
    p.add_argument("--interval", type=positive_ms, default=20, metavar="MS", help="sample period (default 20)")
    p.add_argument("--step", type=float, metavar="ANGLE", help="move to ANGLE degrees first")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--time", type=float, metavar="MS", help="the step takes this long, ms")
    g.add_argument("--speed", type=float, metavar="DPS", help="the step at this speed, °/s")
    p.set_defaults(run=cmd_plot)

    p = sub.add_parser("update", help="firmware update of servos on the bus (0x78), checked before it starts",
                       description=kupdate.__doc__.split("\n\n", 1)[1],
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    kupdate.add_update_arguments(p, False)
    p.set_defaults(standalone=cmd_update)

    p = sub.add_parser("trace", help="scan and read every servo, printing each frame decoded (--move: also move)",
                       description=ksession.__doc__.split("\n\n", 1)[1],
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--move", action="store_true",
                   help="also write a setting (restored afterwards) and move the servos: only with "
                        "nothing attached to them")
    p.set_defaults(standalone=cmd_trace)

    p = sub.add_parser("web", help="the servo wizard: a local web page (scan, control table, plots, update)",
                       description="Serves the servo wizard on http://127.0.0.1:PORT/ (python3-aiohttp): "
                                   "connect to a bus, scan, the control table by name with units, torque, "
                                   "moves and jog, live plots by 0x82, the fault log, set-id, set-baud, "
                                   "rescue and the firmware update. Opens --bus at start when it answers.")
    p.add_argument("--port", type=int, default=8765, help="TCP port on 127.0.0.1 (default 8765; 0 = any free)")
    p.add_argument("--host", default="127.0.0.1", help="address to serve on (default 127.0.0.1)")
    p.add_argument("--any-host", action="store_true", help="allow --host other than this machine")
    p.add_argument("--inject-dir", metavar="DIR", help="the emulated bus's bench (sim/bus/servo-bus --inject-dir "
                   "DIR): supply sag, overheat and load from the page")
    p.set_defaults(standalone=cmd_web)
    return ap


class _CtrlC:
    """SIGINT while kmx runs: the first Ctrl-C raises KeyboardInterrupt
    where the command is (it then closes the bus and says `kmx:
    interrupted`). While the bus closes, and for any later Ctrl-C, it says
    that if not yet said and exits at once: an RFC 2217 close waits for
    pyserial's reader thread and sleeps, and swallows an exception raised
    inside it (a bare except), so raising there would lose the Ctrl-C."""

    def __init__(self):
        self.first = True
        self.closing = False
        self.said = False
        self.previous = None

    def say(self):
        """`kmx: interrupted` on stderr, once."""
        if not self.said:
            self.said = True
            print("kmx: interrupted", file=sys.stderr, flush=True)

    def handle(self, signum, frame):
        """The SIGINT handler (see the class)."""
        if self.first and not self.closing:
            self.first = False
            raise KeyboardInterrupt
        self.say()
        try:
            sys.stdout.flush()
        finally:
            os._exit(130)

    def install(self):
        """Puts handle() in place (signal handlers live in the main thread only)."""
        if threading.current_thread() is threading.main_thread():
            self.previous = signal.signal(signal.SIGINT, self.handle)

    def uninstall(self):
        """The handler from before main(); after an interrupt, none: the
        process is on its way out with status 130 and has said so."""
        if self.previous is not None:
            signal.signal(signal.SIGINT, signal.SIG_IGN if self.said else self.previous)


def run(argv, ctrl_c):
    """Parses the command line, opens the bus, runs the command, closes the bus."""
    args = build_parser().parse_args(argv)
    if getattr(args, "standalone", None):
        return run_standalone(args, ctrl_c)
    bus = None
    try:
        regs_map = RegisterMap.load()
        bus = Bus(args.bus, timeout=args.timeout / 1000.0, retries=args.retries,
                  trace=trace_to_stderr if args.trace else None)
        return args.run(bus, Registers(bus, regs_map), args)
    except KmxError as e:
        print("kmx: %s" % e, file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        ctrl_c.say()
        return 130
    except BrokenPipeError:  # `kmx dump 1 | head`
        return 0
    finally:
        if bus is not None:
            ctrl_c.closing = True
            bus.close()
            ctrl_c.closing = False


def run_standalone(args, ctrl_c):
    """A command that opens the bus itself (update, trace): its status;
    KmxError one line and 1, Ctrl-C one line and 130."""
    try:
        return args.standalone(args)
    except KmxError as e:
        print("kmx: %s" % e, file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        ctrl_c.say()
        return 130


def main(argv=None):
    """The kmx command: its exit status (0, 1 failure, 2 bad command line,
    130 Ctrl-C, which anywhere prints one line and never a traceback)."""
    ctrl_c = _CtrlC()
    ctrl_c.install()
    try:
        return run(argv, ctrl_c)
    except KeyboardInterrupt:  # in the close after the command, or before it
        ctrl_c.say()
        return 130
    finally:
        ctrl_c.closing = True  # a Ctrl-C while the handler goes: one line and 130, never a traceback
        ctrl_c.uninstall()


if __name__ == "__main__":
    sys.exit(main())
