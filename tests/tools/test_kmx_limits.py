# SPDX-License-Identifier: Apache-2.0
"""kmx names what a servo would refuse or clamp before sending it (issue 23
item 5): a value above the bound its product sets (docs/registers.json
"product": 0x10, 0x14, 0x15, 0x17, 0x19, 0x1A, 0x3C, 0x3E, 0x5C, 0x5D) and a
move target outside its angle limits (0x19, 0x1A; docs/protocol.md §5.1)
or its product's travel, which the servo clamps without a word. The product
numbers (host/kmx/products.json, by the model in 0x0A) must be the boards'
own: the table is regenerated from boards/ and protocol/km_registers.def
and compared, and a real host-sim servo refuses (status bit 6, §4) what kmx
refuses. About 4 s."""
import json
import os
import unittest

from test_kmx import REPO, HostSim
from test_kmx_cli import kmx
from kmx import products
from kmx.bus import Bus
from kmx.errors import RangeError
from kmx.registers import Registers


class Table(unittest.TestCase):
    def test_products_json_is_current(self):
        with open(os.path.join(REPO, "host", "kmx", "products.json"), encoding="utf-8") as f:
            shipped = json.load(f)
        self.assertEqual(shipped, json.loads(json.dumps(products.generate(REPO))),
                         "host/kmx/products.json is stale: python3 -m kmx.products --generate . (in host/, REPO ..)")
        self.assertEqual(shipped["bounds"]["0x14"], [0, "current_max_ma"])
        self.assertEqual(shipped["products"]["KM-SIM-P135"]["current_max_ma"], 3000)


class OnHostSim(unittest.TestCase):
    def setUp(self):
        self.sim = HostSim()
        self.addCleanup(self.sim.close)

    def refused(self, message, *args):
        r = kmx(self.sim.spec, *args)
        self.assertEqual((r.returncode, r.stderr), (1, "kmx: %s\n" % message), args)

    def get(self, name):
        return kmx(self.sim.spec, "get", "0", name).stdout

    def test_product_bounds_named_and_nothing_sent(self):
        before = self.get("max_current")
        self.refused("max_current: 5000 mA is above ID 0's limit 3000 mA (current_max_ma of KM-SIM-P135); "
                     "nothing sent", "set", "0", "max_current", "5000")
        self.assertEqual(self.get("max_current"), before)
        self.refused("zero_offset2: -20.0 ° is below ID 0's limit -10.0 ° (-zero_offset2_max of KM-SIM-P135); "
                     "nothing sent", "set", "0", "zero_offset2", "-20")
        self.refused("speed_limit: 800 °/s is above ID 0's limit 360 °/s (speed_max_dps of KM-SIM-P135); "
                     "nothing sent", "set", "0", "speed_limit", "800")
        self.assertEqual(kmx(self.sim.spec, "set", "0", "max_current", "2500").returncode, 0)

    def test_the_servo_refuses_what_kmx_refuses(self):
        """The same writes sent unchecked: the servo sets bit 6 (refused)."""
        with Bus(self.sim.spec) as bus:
            regs = Registers(bus)
            for name, value in (("max_current", 3001), ("speed_limit", 721), ("angle_max", 135.1)):
                with self.subTest(name=name):
                    with self.assertRaises(RangeError):
                        regs.set(0, name, value)
                    regs.set(0, name, value, check=False)
                    self.assertTrue(bus.ping(0) & 0x40, "%s = %s not refused by the servo" % (name, value))

    def test_targets_outside_the_limits(self):
        self.assertEqual(kmx(self.sim.spec, "torque", "0", "on").returncode, 0)
        self.refused("move_time: 150.0 ° is outside ID 0's travel -135.0..135.0 ° (KM-SIM-P135); nothing sent",
                     "move", "0", "150")
        self.assertEqual(kmx(self.sim.spec, "set", "0", "angle_max", "90").returncode, 0)
        self.refused("move_speed: 100.0 ° is outside ID 0's angle limits -135.0 °..90.0 ° (angle_min 0x19, "
                     "angle_max 0x1A): the servo would stop at the limit; nothing sent",
                     "move", "0", "100", "--speed", "90")
        self.refused("interpolate: -140.0 ° is outside ID 0's travel -135.0..135.0 ° (KM-SIM-P135); nothing sent",
                     "set", "0", "interpolate", "-140")
        r = kmx(self.sim.spec, "move", "0", "80", "--time", "200", "--wait")
        self.assertEqual(r.returncode, 0, r.stderr)


if __name__ == "__main__":
    unittest.main()
