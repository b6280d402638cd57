# SPDX-License-Identifier: Apache-2.0
"""The bench of an emulated servo changed at run time: a supply sag, a heat
gun on the case, a load on the horn (docs/web.md "Bench").

sim/bus/servo-bus --inject-dir DIR gives each host-sim servo a Unix
datagram socket DIR/servo-ID.sock (host-sim --inject): one "KEY VALUE" per
datagram, with the keys of a --scenario file
(boards/sim-common/km_sim_scenario.h), applied to the servo's simulated
plant at once and answered "ok KEY VALUE" or "error: reason". A real bus has
no such thing: the servo's own sensors see the real supply and heat.

    bench = Bench("/tmp/bench")
    bench.inject(1, "supply_mv", 5000)    # the supply sags to 5.0 V
"""

import os
import socket
import time

from .errors import KmxError

# key -> (what it is, unit of the number, lo, hi): host-sim's ranges (hs_scenario.c)
KEYS = {
    "supply_mv": ("open-circuit supply", "mV", 0, 65535),
    "ambient_dc": ("ambient temperature", "0.1 °C", -2730, 3000),
    "load_mnm": ("external torque on the horn", "mN·m", -100000, 100000),
    "faults": ("plant faults (1 pot, 2 motor, 4 NTC open)", "mask", 0, 7),
    "temp_dc": ("the winding's temperature now", "0.1 °C", -400, 2000),
}

# name -> (button words, events): the bench of tests/bus/scenarios/protect.txt by hand;
# "normal" is the simulated plant's power-on bench (sim/plant/km_plant_default.c)
PRESETS = {
    "sag": ("Supply sags to 5.0 V", [("supply_mv", 5000)]),
    "overheat": ("Heat the case to 65 °C", [("ambient_dc", 650), ("temp_dc", 650)]),
    "normal": ("Back to normal: 7.4 V, 25 °C, no load",
               [("supply_mv", 7400), ("ambient_dc", 250), ("temp_dc", 250), ("load_mnm", 0)]),
}


class Bench:
    """The inject sockets of one emulated bus (servo-bus --inject-dir DIR)."""

    def __init__(self, inject_dir):
        self.dir = os.path.abspath(inject_dir)

    def path(self, dev_id):
        return os.path.join(self.dir, "servo-%d.sock" % dev_id)

    def servos(self):
        """The IDs with an inject socket (the IDs servo-bus launched them with)."""
        try:
            names = os.listdir(self.dir)
        except OSError:
            return []
        return sorted(int(n[6:-5]) for n in names
                      if n.startswith("servo-") and n.endswith(".sock") and n[6:-5].isdigit())

    def inject(self, dev_id, key, value, timeout=5.0):
        """Sends "KEY VALUE" to dev_id's plant; its answer ("ok ..."). Raises
        KmxError in words: a key or value the bench does not take, no socket
        for dev_id, or no answer within `timeout` s (a restarting servo binds
        its socket again: retried until then)."""
        if key not in KEYS:
            raise KmxError("bench: no key %r (%s)" % (key, ", ".join(KEYS)))
        what, unit, lo, hi = KEYS[key]
        if not isinstance(value, int) or not lo <= value <= hi:
            raise KmxError("bench: %s (%s) takes %d..%d %s, not %r" % (key, what, lo, hi, unit, value))
        path = self.path(dev_id)
        if not os.path.exists(path):
            raise KmxError("bench: ID %d has no inject socket in %s (servo-bus --inject-dir names each servo "
                           "by the ID it was launched with)" % (dev_id, self.dir))
        return self._send(path, ("%s %d" % (key, value)).encode(), timeout)

    def _send(self, path, data, timeout):
        """One datagram to path and its answer, retried until timeout."""
        end = time.monotonic() + timeout
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
            s.bind("")  # an address of our own (Linux autobind): host-sim answers to it
            while True:
                try:
                    s.sendto(data, path)
                    s.settimeout(max(0.05, min(1.0, end - time.monotonic())))
                    answer = s.recv(256).decode(errors="replace")
                    break
                except (ConnectionRefusedError, FileNotFoundError, socket.timeout):
                    if time.monotonic() >= end:
                        raise KmxError("bench: no answer from %s within %.0f s (is the servo running?)"
                                       % (path, timeout)) from None
                    time.sleep(0.05)
        if not answer.startswith("ok "):
            raise KmxError("bench: %s refused %s: %s" % (path, data.decode(), answer))
        return answer
