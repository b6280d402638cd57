"""The `kmx` command: find servos on a bus and read and set their registers
by name, with units (names, units and ranges from docs/registers.json).

  kmx [--bus SPEC] scan                 every servo: ID, baud, model, firmware, status
  kmx [--bus SPEC] ping ID
  kmx [--bus SPEC] get ID NAME...       e.g. kmx get 1 position voltage
  kmx [--bus SPEC] set ID NAME VALUE... e.g. kmx set 1 move_time 45 500
  kmx [--bus SPEC] dump ID              every register, decoded

SPEC: tcp:HOST:PORT (tools/servo-bus, host-sim), serial:/dev/ttyUSB0@115200,
pty:/dev/pts/N; default $KMX_BUS, else tcp:127.0.0.1:7000. Failures print
one line `kmx: ...` and exit 1 (2 for a bad command line), never a traceback.
"""

import argparse
import os
import sys
import time

from . import frame as fr
from .bus import SCAN_TIMEOUT, Bus
from .errors import KmxError, NoAnswer, RegisterError
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


def positive_ms(text):
    try:
        v = float(text)
    except ValueError:
        v = -1
    if v <= 0:
        raise argparse.ArgumentTypeError("'%s' is not a positive number of milliseconds" % text)
    return v


def _table(rows, header):
    widths = [max(len(str(r[i])) for r in rows + [header]) for i in range(len(header))]
    fmt = "  ".join("%%-%ds" % w for w in widths)
    return "\n".join((fmt % tuple(r)).rstrip() for r in [header] + rows)


def cmd_scan(bus, regs, args):
    t0 = time.monotonic()
    found = bus.scan(timeout=args.scan_ms / 1000.0)
    if not found:
        raise NoAnswer("no servo answered the super-ID ping within %.0f ms on %s"
                       % (args.scan_ms, bus.transport.spec))
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
    order = [i for i, _ in found]
    note = "" if order == sorted(order) else " (answers out of ID order: %s)" % order
    print("%d servo%s on %s (super-ID scan, %.0f ms)%s" % (
        len(found), "" if len(found) == 1 else "s", bus.transport.spec, 1000 * (time.monotonic() - t0), note))
    return 0


def cmd_ping(bus, regs, args):
    t0 = time.monotonic()
    status = bus.ping(args.id)
    print("ID %d: status 0x%02X (%s), answered in %.1f ms" % (
        args.id, status, ", ".join(fr.status_words(status)), 1000 * (time.monotonic() - t0)))
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
    bus.write(args.id, reg.address, data)
    # §3: the new ID applies right after the write; §4: bit 6 = the write
    # was refused, bit 5 = not supported
    now_id = data[0] if reg.address == fr.REG_ID else args.id
    try:
        status = bus.ping(now_id)
    except NoAnswer:
        if reg.address == fr.REG_ID:
            raise NoAnswer("wrote id = %d to ID %d, but nothing answers at ID %d" % (now_id, args.id, now_id)) from None
        raise
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
                                           else data.hex(" ").upper(), data.hex(" ").upper()))
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


def build_parser():
    ap = argparse.ArgumentParser(prog="kmx", description=__doc__.split("\n\n")[0],
                                 epilog=__doc__.split("\n\n", 1)[1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bus", default=os.environ.get("KMX_BUS", DEFAULT_BUS),
                    help="the bus: tcp:HOST:PORT, serial:DEVICE@BAUD or pty:PATH (default $KMX_BUS or %s)"
                    % DEFAULT_BUS)
    ap.add_argument("--timeout", type=positive_ms, default=100, metavar="MS",
                    help="wait for one answer, ms (default 100)")
    ap.add_argument("--retries", type=int, default=2, choices=range(0, 10), metavar="N",
                    help="extra tries of a read or ping (default 2)")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser("scan", help="find every servo (super-ID ping) with its baud, model, firmware, status",
                       description="Pings the super ID (0xFD): every servo answers in its own slot, in ID "
                                   "order; then reads each one's baud, model and firmware.")
    p.add_argument("--scan-ms", type=positive_ms, default=SCAN_TIMEOUT * 1000, metavar="MS",
                   help="listen this long for answers (default %.0f; ID 250 answers last)" % (SCAN_TIMEOUT * 1000))
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
    return ap


def main(argv=None):
    args = build_parser().parse_args(argv)
    bus = None
    try:
        regs_map = RegisterMap.load()
        bus = Bus(args.bus, timeout=args.timeout / 1000.0, retries=args.retries)
        return args.run(bus, Registers(bus, regs_map), args)
    except KmxError as e:
        print("kmx: %s" % e, file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("kmx: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `kmx dump 1 | head`
        return 0
    finally:
        if bus is not None:
            bus.close()


if __name__ == "__main__":
    sys.exit(main())
