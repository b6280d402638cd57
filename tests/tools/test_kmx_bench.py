# SPDX-License-Identifier: Apache-2.0
"""kmx.bench follows the servo, not the socket's name (docs/web.md "Bench"):
servo-bus --inject-dir names each host-sim servo's inject socket by the ID
it was launched with, but `kmx set-id` moves a servo to another ID while it
runs. Bench(DIR).inject(N, ...) must reach the servo that answers at ID N
on the bus now: here two servos launched as 1 and 2 swap IDs (1 -> 3,
2 -> 1), a supply sag injected into ID 1 must show on ID 1's voltage over
the bus (docs/protocol.md §5.2, 0x4B) and not on ID 3's; an ID two servos
share, or none answers at, is refused in words. Needs the host-sim preset;
about 10 s."""
import os
import tempfile
import time
import unittest

from test_kmx import ServoBus
from kmx import frame as fr
from kmx.bench import Bench
from kmx.bus import Bus
from kmx.errors import KmxError
from kmx.registers import RegisterMap, Registers


class BenchFollowsTheLiveId(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory(prefix="kmx-bench-")
        cls.wire = ServoBus(ids=(1, 2), extra=("--inject-dir", cls.tmp.name))
        cls.bus = Bus(cls.wire.spec, timeout=0.3, retries=3)
        cls.regs = Registers(cls.bus, RegisterMap.load())
        cls.bench = Bench(cls.tmp.name)

    @classmethod
    def tearDownClass(cls):
        cls.bus.close()
        cls.wire.close()
        cls.tmp.cleanup()

    def set_id(self, old, new):
        """0x0F written (§3: applies at once), as kmx set-id does before its restart."""
        self.bus.write(old, fr.REG_ID, bytes([new]))
        self.bus.ping(new)

    def volts(self, dev_id):
        return self.regs.get(dev_id, "voltage").value

    def volts_until(self, dev_id, check, what, seconds=30):
        """Reads dev_id's voltage over the bus until check(volts) holds (generous: a loaded machine)."""
        end = time.monotonic() + seconds
        while True:
            v = self.volts(dev_id)
            if check(v):
                return v
            if time.monotonic() > end:
                self.fail("%s: ID %d reads %.3f V after %d s" % (what, dev_id, v, seconds))
            time.sleep(0.1)

    def test_inject_reaches_the_servo_at_its_new_id(self):
        self.assertEqual(sorted(os.listdir(self.tmp.name)), ["servo-1.sock", "servo-2.sock"])
        self.set_id(1, 3)  # launched as 1, now ID 3
        self.set_id(2, 1)  # launched as 2, now ID 1
        try:
            self.assertEqual(self.bench.servos(), [1, 3])
            self.assertEqual(self.bench.inject(1, "supply_mv", 5000), "ok supply_mv 5000")
            self.volts_until(1, lambda v: v < 5.2, "the sag on the servo now at ID 1")
            self.assertGreater(self.volts(3), 7.2, "the sag reached the servo launched as ID 1, now ID 3")
            self.bench.inject(1, "supply_mv", 7400)
            self.volts_until(1, lambda v: v > 7.2, "the supply back to 7.4 V at ID 1")
            with self.assertRaises(KmxError) as e:
                self.bench.inject(2, "supply_mv", 5000)
            self.assertEqual(str(e.exception), "bench: no servo with a bench answers at ID 2 now "
                                               "(the bench's servos are at ID 1, 3)")
        finally:
            self.set_id(1, 2)
            self.set_id(3, 1)
        self.assertEqual(self.bench.servos(), [1, 2])



class BenchRefusesASharedId(unittest.TestCase):
    """Two servos on one ID (stored IDs in --flash-dir: the servo launched as 1
    was moved to 2 in an earlier run): which one is meant is not known, so the
    bench refuses it in words and names the command that separates them."""

    def test_a_shared_id_is_refused(self):
        with tempfile.TemporaryDirectory(prefix="kmx-bench-") as tmp:
            flash, inject = os.path.join(tmp, "flash"), os.path.join(tmp, "inject")
            os.mkdir(flash)
            os.mkdir(inject)
            wire = ServoBus(ids=(1,), extra=("--flash-dir", flash))
            try:
                with Bus(wire.spec, timeout=0.3, retries=3) as bus:
                    bus.write(1, fr.REG_ID, bytes([2]))
                    bus.restart(2)  # stored: it comes back at ID 2
            finally:
                wire.close()
            wire = ServoBus(ids=(1, 2), extra=("--flash-dir", flash, "--inject-dir", inject))
            try:
                bench = Bench(inject)
                self.assertEqual(bench.servos(), [2])
                with self.assertRaises(KmxError) as e:
                    bench.inject(2, "supply_mv", 5000)
                self.assertEqual(str(e.exception), "bench: 2 servos with a bench answer at ID 2: separate them "
                                                   "first (kmx scan names the command)")
            finally:
                wire.close()

if __name__ == "__main__":
    unittest.main()
