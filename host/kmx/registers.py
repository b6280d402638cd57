# SPDX-License-Identifier: Apache-2.0
"""Registers by name with units (docs/protocol.md §5), loaded from the
machine-readable description the firmware's register list generates
(docs/registers.json, `km_regdoc --json`): lookup by name or address,
decoding by wire layout into values in units, encoding from units with
type and range checks before anything is sent.

    regs = RegisterMap.load()
    regs["voltage"].decode(b"\\xE8\\x1C")  -> Value, str() "7.400 V"
    regs["move_time"].encode("45, 500")   -> b"\\xC2\\x01\\xF4\\x01"
    Registers(bus).get(1, "position")     -> Value, str() "45.0 °"
"""

import difflib
import json
import math
import os
from importlib import resources

from . import frame as fr
from .errors import RangeError, RegisterError
from .frame import status_words

ENV_PATH = "KMX_REGISTERS"  # overrides where registers.json is read from
_HERE = os.path.dirname(os.path.abspath(__file__))
CHECKOUT_PATH = os.path.join(_HERE, "..", "..", "docs", "registers.json")  # the checkout (host/kmx -> docs)


def _package_description():
    """registers.json shipped in the package (importlib.resources: an
    installed wheel, a zip, the checkout's symlink to docs/): (where, text)
    or None."""
    try:
        res = resources.files("kmx").joinpath("registers.json")
        return str(res), res.read_text(encoding="utf-8")
    except (FileNotFoundError, OSError, ModuleNotFoundError):
        return None


_INT_TYPES = {  # wire type -> (bytes, signed)
    "u8": (1, False), "bits8": (1, False), "i8": (1, True),
    "u16": (2, False), "i16": (2, True), "u32": (4, False), "x16": (2, None),
}


def _decimals(scale):
    """Digits after the point a scale needs: 0.1 -> 1, 0.001 -> 3, 100 -> 0."""
    text = ("%.10f" % scale).rstrip("0")
    return len(text.split(".")[1]) if "." in text else 0


class Value:
    """A decoded register value: raw (the wire integers, text or bytes),
    fields (numbers in units) and a display text with units."""

    def __init__(self, register, raw, fields, text):
        self.register = register
        self.raw = raw
        self.fields = fields
        self.text = text

    @property
    def value(self):
        """The first field in units (the value most registers have)."""
        return self.fields[0] if self.fields else None

    def __str__(self):
        return self.text

    def __repr__(self):
        return "<%s = %s>" % (self.register.name, self.text)


class Register:
    def __init__(self, d):
        self.address = d["address"]
        self.name = d["name"]
        self.title = d["title"]
        self.access = d["access"]
        self.persisted = d["persisted"]
        self.layout = d["layout"]
        self.type = d["type"]
        self.lengths = d["lengths"]
        self.default = d["default"]
        self.fields = d["fields"]
        self.description = d["description"]

    readable = property(lambda self: "R" in self.access)
    writable = property(lambda self: "W" in self.access)

    def __repr__(self):
        return "<Register 0x%02X %s>" % (self.address, self.name)

    # -- units ---------------------------------------------------------------
    def unit(self, field=0):
        return self.fields[field]["unit"] if field < len(self.fields) else ""

    def decimals(self, field=0):
        """Digits after the point a value in units needs (position 1, voltage 3)."""
        f = self.fields[field]
        return _decimals(f["scale"]) if f["unit"] else 0

    def _format_field(self, raw, field):
        f = self.fields[field]
        if f["type"] == "bits8":
            return "0x%02X" % raw
        if f["unit"] == "":
            # a unit-less byte is a code or packed bit pairs (0x34): hex too
            return "%d (0x%02X)" % (raw, raw) if f["type"] == "u8" and raw >= 10 else "%d" % raw
        d = _decimals(f["scale"])
        return "%.*f %s" % (d, raw * f["scale"], f["unit"])

    def _in_units(self, raw, field):
        f = self.fields[field]
        if f["unit"] == "":
            return raw
        v = raw * f["scale"]
        return round(v, _decimals(f["scale"])) if _decimals(f["scale"]) else int(round(v))

    # -- decoding --------------------------------------------------------------
    def decode(self, data):
        """Wire bytes of a read answer -> Value. Raises RangeError when the
        length does not fit the layout."""
        data = bytes(data)
        if len(data) not in self.lengths:
            raise RangeError("%s (0x%02X): answer of %d bytes, expected %s" % (
                self.name, self.address, len(data), " or ".join(map(str, self.lengths))))
        lay = self.layout
        if lay == "text":
            text = data.rstrip(b"\0").decode("ascii", "replace")
            return Value(self, text, [text], text)
        if lay == "magic":
            return Value(self, data, [data], data.hex(" ").upper())
        if lay == "status":
            words = ", ".join(status_words(data[0]))
            return Value(self, [data[0], data[1]], [data[0], data[1]],
                         "0x%02X (%s), random 0x%02X" % (data[0], words, data[1]))
        if lay == "u32":
            v = int.from_bytes(data, "little")
            text = ("0x%08X" % v) if self.fields[0]["unit"] == "" else self._format_field(v, 0)
            return Value(self, [v], [self._in_units(v, 0)], text)
        if lay == "pos":
            v = int.from_bytes(data, "little", signed=True)
            return Value(self, [v], [self._in_units(v, 0)], self._format_field(v, 0))
        if lay == "adv":
            raw = [data[0], int.from_bytes(data[1:3], "little"), int.from_bytes(data[3:5], "little")]
            return Value(self, raw, raw, "0x%02X, %d, %d" % tuple(raw))
        raw = []
        pos = 0
        for i, f in enumerate(self.fields):
            size, signed = _INT_TYPES[f["type"]]
            if pos + size > len(data):
                break  # an optional second field left out
            raw.append(int.from_bytes(data[pos:pos + size], "little", signed=bool(signed)))
            pos += size
        fields = [self._in_units(r, i) for i, r in enumerate(raw)]
        text = ", ".join(self._format_field(r, i) for i, r in enumerate(raw))
        return Value(self, raw, fields, text)

    # -- encoding --------------------------------------------------------------
    def _parse_number(self, v, field):
        unit = self.unit(field)
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            num = v
        else:
            s = str(v).strip()
            if unit and s.endswith(unit):
                s = s[: -len(unit)].strip()
            try:
                num = int(s, 0)
            except ValueError:
                try:
                    num = float(s)
                except ValueError:
                    raise RangeError("%s: '%s' is not a number%s" % (
                        self.name, v, " (in %s)" % unit if unit else "")) from None
        if isinstance(num, float) and not math.isfinite(num):
            raise RangeError("%s: %s is not a finite number" % (self.name, v))
        return num

    def _raw_of(self, v, field):
        """A number in units -> the wire integer, checked against the type
        and the register's range."""
        f = self.fields[field]
        scale = f["scale"] if f["unit"] else 1
        num = self._parse_number(v, field)
        raw = num / scale if scale != 1 else num
        if isinstance(raw, float):
            if abs(raw - round(raw)) > 1e-6:
                if f["unit"] == "":
                    raise RangeError("%s: %s is not a whole number" % (self.name, v))
                step = "%.*f %s" % (_decimals(scale), scale, f["unit"])
                raise RangeError("%s: %s is not a multiple of %s" % (self.name, v, step))
            raw = int(round(raw))
        size, signed = _INT_TYPES[f["type"]]
        lo, hi = ((-(1 << (8 * size - 1)), (1 << (8 * size - 1)) - 1) if signed
                  else (0, (1 << (8 * size)) - 1))
        if signed is None:  # a 16-bit parameter of 0x67/0x70: either reading
            lo, hi = -(1 << 15), (1 << 16) - 1
        for key, cmp in (("min", max), ("max", min)):
            b = f.get(key)
            if isinstance(b, int):
                if key == "min":
                    lo = cmp(lo, b)
                else:
                    hi = cmp(hi, b)
        if not lo <= raw <= hi:
            show = (lambda r: self._format_field(r, field)) if f["unit"] else str
            raise RangeError("%s: %s is outside %s..%s" % (self.name, show(raw), show(lo), show(hi)))
        return raw, size

    def encode(self, value):
        """A value in units -> wire bytes: a number or text for one field;
        a list, tuple or "a, b" text for several (0x65: "45, 500" = 45.0 °
        in 500 ms). Raises RegisterError for a read-only register and
        RangeError for a value it cannot take; nothing is sent."""
        if not self.writable:
            raise RegisterError("%s (0x%02X) is read-only" % (self.name, self.address))
        if self.layout == "magic":
            if isinstance(value, (bytes, bytearray)):
                data = bytes(value)
            else:
                text = " ".join(map(str, value)) if isinstance(value, (list, tuple)) else str(value)
                try:
                    data = bytes.fromhex(text)
                except ValueError:
                    data = b""
            if len(data) != 4:
                raise RangeError("%s: takes exactly 4 bytes in hex (E1 E2 E3 E4), got '%s'" % (self.name, value))
            return data
        if self.layout == "pos":
            num = self._parse_number(value, 0)
            raw = int(round(num / self.fields[0]["scale"]))
            size = 2 if -(1 << 15) <= raw < (1 << 15) else 4
            if not -(1 << 31) <= raw < (1 << 31):
                raise RangeError("%s: %s does not fit i32" % (self.name, value))
            return raw.to_bytes(size, "little", signed=True)
        if isinstance(value, str):
            units = {f["unit"] for f in self.fields if f["unit"]}
            parts = [p for p in value.replace(",", " ").split() if p not in units]  # "45 °, 500 ms"
        elif isinstance(value, (list, tuple)):
            parts = list(value)
        else:
            parts = [value]
        needed = sum(1 for f in self.fields if not f.get("optional"))
        if not needed <= len(parts) <= len(self.fields):
            raise RangeError("%s: takes %s value%s (%s), got %d" % (
                self.name, needed if needed == len(self.fields) else "%d or %d" % (needed, len(self.fields)),
                "" if len(self.fields) == 1 else "s", self.type, len(parts)))
        out = b""
        for i, p in enumerate(parts):
            raw, size = self._raw_of(p, i)
            signed = raw < 0
            out += raw.to_bytes(size, "little", signed=signed)
        return out


class RegisterMap:
    """All registers of docs/registers.json, by name and by address."""

    def __init__(self, description):
        self.registers = [Register(d) for d in description["registers"]]
        self.by_name = {r.name: r for r in self.registers}
        self.by_address = {r.address: r for r in self.registers}

    @classmethod
    def load(cls, path=None):
        """The register description: `path`, else $KMX_REGISTERS, else the
        package's registers.json (package data), else the checkout's
        docs/registers.json. RegisterError naming where it looked."""
        if path or os.environ.get(ENV_PATH):
            return cls._load_file(path or os.environ[ENV_PATH])
        shipped = _package_description()
        if shipped is not None:
            return cls._parse(shipped[0], shipped[1])
        if os.path.isfile(CHECKOUT_PATH):
            return cls._load_file(CHECKOUT_PATH)
        raise RegisterError("no register description found (kmx/registers.json is missing from the package "
                            "and no checkout at %s); reinstall kmx or set %s" % (CHECKOUT_PATH, ENV_PATH))

    @classmethod
    def _load_file(cls, p):
        """A register description from a file; RegisterError when it is absent or unreadable."""
        try:
            with open(p, encoding="utf-8") as f:
                return cls._parse(p, f.read())
        except OSError as e:
            raise RegisterError("register description %s is unreadable: %s" % (p, e.strerror or e)) from None

    @classmethod
    def _parse(cls, where, text):
        """A RegisterMap from JSON text read from `where` (kept in .source)."""
        try:
            out = cls(json.loads(text))
        except (ValueError, KeyError, TypeError) as e:
            raise RegisterError("register description %s is unreadable: %s" % (where, e)) from None
        out.source = where
        return out

    def __iter__(self):
        return iter(self.registers)

    def __len__(self):
        return len(self.registers)

    def __getitem__(self, key):
        return self.find(key)

    def find(self, key):
        """A register by name (any case, - or _), address (int) or "0x46"."""
        if isinstance(key, int):
            addr = key
        else:
            s = str(key).strip()
            name = s.lower().replace("-", "_")
            if name in self.by_name:
                return self.by_name[name]
            try:
                addr = int(s, 0)
            except ValueError:
                close = difflib.get_close_matches(name, self.by_name, 3)
                raise RegisterError("no register named '%s'%s" % (
                    s, "; did you mean %s?" % ", ".join(close) if close else "")) from None
        if addr in self.by_address:
            return self.by_address[addr]
        raise RegisterError("no register at address 0x%02X (reserved)" % addr if 0 <= addr <= 0xFF
                            else "address %d is not a byte" % addr)


class Registers:
    """Register access by name with units over a Bus."""

    def __init__(self, bus, regmap=None):
        self.bus = bus
        self.map = regmap or RegisterMap.load()
        self._limits = None
        # Servos that left a multi-ID read (0x82) unanswered: read_each reads them by 0x02 from then on.
        self.no_multi_read = set()

    def get(self, dev_id, key, timeout=None):
        reg = self.map.find(key)
        if not reg.readable:
            raise RegisterError("%s (0x%02X) is write-only" % (reg.name, reg.address))
        return reg.decode(self.bus.read(dev_id, reg.address, timeout))

    def set(self, dev_id, key, value, answer=False, check=True):
        """Encodes (checks first) and writes; returns the status if answer=True.
        check=True also checks the value against what the servo's product
        allows and a move target against its angle limits (kmx/products.py):
        RangeError naming the limit, nothing sent."""
        reg = self.map.find(key)
        data = reg.encode(value)
        if check:
            self.check(dev_id, reg, data)
        return self.bus.write(dev_id, reg.address, data, answer=answer)

    def get_many(self, ids, key, timeout=None):
        """One register of many servos in one multi-ID read (0x82,
        docs/protocol-decisions.md): {id: Value}, None for a servo that did
        not answer."""
        reg = self.map.find(key)
        if not reg.readable:
            raise RegisterError("%s (0x%02X) is write-only" % (reg.name, reg.address))
        got = self.bus.multi_read(reg.address, ids, timeout)
        return {i: None if data is None else reg.decode(data) for i, data in got.items()}

    def read_each(self, ids, key):
        """One register of many servos, each servo read once: one multi-ID
        read (0x82) for every servo not known to lack it, then a read (0x02)
        of each servo that did not answer it. A servo that leaves an 0x82
        listing it unanswered (a build without 0x82, such as the 32 KiB
        STM32G031F6 one: docs/footprint.md "What gives way") is remembered
        in no_multi_read for the life of this object (the bus session) and
        read by 0x02 only from then on: each 0x82 it does not take sets its
        status bit 5 (§4, unsupported command), so its status reports bit 5
        once, after the first 0x82, and not on every call. {id: Value}."""
        multi = [i for i in ids if i not in self.no_multi_read]
        got = self.get_many(multi, key) if multi else {}
        self.no_multi_read.update(i for i in multi if got[i] is None)
        return {i: got[i] if got.get(i) is not None else self.get(i, key) for i in ids}

    def _encode_many(self, reg, values, check):
        """{id: value in units} -> [(id, bytes)], every value checked first."""
        entries = []
        for dev_id, value in (values.items() if isinstance(values, dict) else values):
            data = reg.encode(value)
            if check:
                self.check(dev_id, reg, data)
            entries.append((dev_id, data))
        return entries

    def set_many(self, key, values, check=True):
        """Each servo its own value of one register in one multi-ID write
        (0x83, §3: 0x64, 0x65, 0x66, 0x68, 0x6E, 0x6F): values {id: value in
        units}. Every value is encoded and checked before the frame goes out."""
        reg = self.map.find(key)
        if reg.address not in fr.MULTI_WRITE_ADDRESSES:
            raise RegisterError("%s (0x%02X) cannot go in a multi-ID write (0x83 takes %s); use sync_set"
                                % (reg.name, reg.address, ", ".join("0x%02X" % a for a in fr.MULTI_WRITE_ADDRESSES)))
        self.bus.multi_write(reg.address, self._encode_many(reg, values, check))

    def sync_set(self, key, values, check=True, execute=True):
        """Each servo its own value of any writable register, acted on at
        once: a sync write (0x04) to each, then one broadcast execute (0x84)
        unless execute=False."""
        reg = self.map.find(key)
        for dev_id, data in self._encode_many(reg, values, check):
            self.bus.sync_write(dev_id, reg.address, data)
        if execute:
            self.bus.execute()

    def check(self, dev_id, reg, data):
        """RangeError when the servo would refuse data for reg (a product
        bound) or clamp it (a move target outside its angle limits)."""
        if self._limits is None:
            from .products import Limits
            self._limits = Limits(self.bus, self.map)
        self._limits.check_write(dev_id, reg, data)
