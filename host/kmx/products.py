# SPDX-License-Identifier: Apache-2.0
"""What a servo will refuse or clamp, known before a frame is sent.

docs/registers.json marks the bounds that depend on the product ("product":
0x10, 0x14, 0x15, 0x17, 0x19, 0x1A, 0x3C, 0x3E, 0x5C, 0x5D); products.json
(package data, made from the boards' product files and
protocol/km_registers.def by `python3 -m kmx.products --generate REPO`)
gives each known model's numbers, by the model name a servo reports in 0x0A.
A move target outside the servo's angle limits (0x19, 0x1A; 0 = none) or
its product's travel is clamped by the servo without a word (control's
km_servo_mode.c): kmx names it instead, before sending.

    limits = Limits(bus, regmap)
    limits.check_write(1, reg, data)   # RangeError naming the limit, or None
    limits.check_target(1, 150.0)      # RangeError naming 0x19/0x1A or travel
"""

import json
import os
import re
import sys
from importlib import resources

from .errors import KmxError, RangeError

MOVE_REGISTERS = (0x65, 0x66, 0x68)  # their first field is an absolute target, 0.1 °
DEF_BOUND = re.compile(r"^KM_REG\((0x[0-9A-Fa-f]{2}),\s*\w+,\s*\w+,\s*\d,\s*\w+,\s*(.*?),\s*([^,]+),\s*([^,]+),"
                       r"\s*[^,]+,\s*\w+,\s*\w+\)", re.M)
PRODUCT_BLOCK = re.compile(r"km_product_t\s+\w+\s*=\s*\{(.*?)\n\};", re.S)
PRODUCT_FIELD = re.compile(r"^\s*\.(\w+)\s*=\s*(\"[^\"]*\"|-?\d+)\s*,", re.M)


def load_products():
    """products.json from the package (importlib.resources), or {} when absent."""
    try:
        text = resources.files("kmx").joinpath("products.json").read_text(encoding="utf-8")
    except (FileNotFoundError, OSError):
        return {"bounds": {}, "products": {}}
    return json.loads(text)


class Limits:
    """Checks a write or a move target of one servo against its product's
    bounds and its angle limits, reading 0x0A, 0x19 and 0x1A once per ID."""

    def __init__(self, bus, regmap, table=None):
        self.bus, self.map = bus, regmap
        self.table = table or load_products()
        self._model = {}

    def product(self, dev_id):
        """(model name, its numbers or None when kmx does not know the model)."""
        if dev_id not in self._model:
            reg = self.map.find("product_info")
            try:
                self._model[dev_id] = reg.decode(self.bus.read(dev_id, reg.address)).value
            except KmxError:
                self._model[dev_id] = None
        model = self._model[dev_id]
        return model, self.table["products"].get(model) if model else None

    def _bound(self, numbers, term):
        """A bound term of km_registers.def: a number, a product field or its negative."""
        if not isinstance(term, str):
            return term
        return -numbers[term[1:]] if term.startswith("-") else numbers[term]

    def check_write(self, dev_id, reg, data):
        """RangeError when the value bytes data for reg exceed a bound the
        servo's product sets; move targets as check_target. None otherwise."""
        if reg.address in MOVE_REGISTERS:
            raw = int.from_bytes(bytes(data)[:2], "little", signed=True)
            self.check_target(dev_id, raw * reg.fields[0]["scale"], reg.name)
        bound = self.table["bounds"].get("0x%02X" % reg.address)
        if bound is None:
            return
        model, numbers = self.product(dev_id)
        if numbers is None:
            return  # an unknown model: the servo's own check decides (bit 6)
        lo, hi = self._bound(numbers, bound[0]), self._bound(numbers, bound[1])
        for i, raw in enumerate(reg.decode(data).raw):
            if reg.fields[i].get("max") != "product" and reg.fields[i].get("min") != "product":
                continue
            if not lo <= raw <= hi:
                show = lambda r: reg._format_field(r, i)  # noqa: E731
                which = bound[1] if raw > hi else bound[0]
                raise RangeError("%s: %s is %s ID %d's limit %s (%s of %s); nothing sent" % (
                    reg.name, show(raw), "above" if raw > hi else "below", dev_id,
                    show(hi if raw > hi else lo), which, model))

    def check_target(self, dev_id, target_deg, what="target"):
        """RangeError when target_deg lies outside ID dev_id's angle limits
        (0x19, 0x1A, 0 = no limit) or its product's travel: the servo would
        clamp it to the nearest end."""
        model, numbers = self.product(dev_id)
        lo_reg, hi_reg = self.map.find("angle_min"), self.map.find("angle_max")
        lo = lo_reg.decode(self.bus.read(dev_id, lo_reg.address)).value
        hi = hi_reg.decode(self.bus.read(dev_id, hi_reg.address)).value
        if numbers is not None:
            travel = (numbers["travel_min"] / 10.0, numbers["travel_max"] / 10.0)
            if not travel[0] <= target_deg <= travel[1]:
                raise RangeError("%s: %.1f ° is outside ID %d's travel %.1f..%.1f ° (%s); nothing sent" % (
                    what, target_deg, dev_id, travel[0], travel[1], model))
        low_ok = lo == 0 or target_deg >= lo
        high_ok = hi == 0 or target_deg <= hi
        if not (low_ok and high_ok):
            raise RangeError("%s: %.1f ° is outside ID %d's angle limits %s..%s (angle_min 0x19, angle_max "
                             "0x1A): the servo would stop at the limit; nothing sent" % (
                                 what, target_deg, dev_id, "%.1f °" % lo if lo else "none",
                                 "%.1f °" % hi if hi else "none"))


def _bound_term(text):
    """A min or max column of km_registers.def: 'p->x' -> 'x', '-p->x' -> '-x', a number -> int, else None."""
    text = text.strip()
    if text.startswith(("p->", "-p->")):
        return text.replace("p->", "")
    try:
        return int(text, 0)
    except ValueError:
        return None


def generate(repo):
    """The products.json content: every km_product_t of boards/ by model,
    and every register whose range km_registers.def takes from the product."""
    with open(os.path.join(repo, "protocol", "km_registers.def"), encoding="utf-8") as f:
        rows = DEF_BOUND.findall(f.read())
    bounds = {}
    for addr, _default, lo, hi in rows:
        lo_t, hi_t = _bound_term(lo), _bound_term(hi)
        if isinstance(lo_t, str) or isinstance(hi_t, str):
            bounds["0x%02X" % int(addr, 16)] = [lo_t, hi_t]
    products = {}
    for root, _dirs, files in sorted(os.walk(os.path.join(repo, "boards"))):
        for name in sorted(files):
            if not name.endswith(".c"):
                continue
            with open(os.path.join(root, name), encoding="utf-8") as f:
                for block in PRODUCT_BLOCK.findall(f.read()):
                    fields = {k: (v.strip('"') if v.startswith('"') else int(v))
                              for k, v in PRODUCT_FIELD.findall(block)}
                    if "model" in fields:
                        products[fields.pop("model")] = fields
    return {"comment": "made by `python3 -m kmx.products --generate REPO` from boards/*/ product files and "
                       "protocol/km_registers.def; tests/tools/test_kmx_limits.py checks it is current",
            "bounds": bounds, "products": dict(sorted(products.items()))}


def main(argv):
    """--generate REPO [OUT]: writes products.json (default: next to this module)."""
    if len(argv) < 2 or argv[0] != "--generate":
        print("usage: python3 -m kmx.products --generate REPO [OUT]", file=sys.stderr)
        return 2
    out = argv[2] if len(argv) > 2 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "products.json")
    with open(out, "w", encoding="utf-8") as f:
        json.dump(generate(argv[1]), f, indent=1, ensure_ascii=False)
        f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
