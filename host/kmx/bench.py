# SPDX-License-Identifier: Apache-2.0
"""The bench of an emulated servo changed at run time: a supply sag, a heat
gun on the case, a load on the horn (docs/web.md "Bench").

sim/bus/servo-bus --inject-dir DIR gives each host-sim servo a Unix
datagram socket DIR/servo-ID.sock (host-sim --inject): one "KEY VALUE" per
datagram, with the keys of a --scenario file
(boards/sim-common/km_sim_scenario.h), applied to the servo's simulated
plant at once and answered "ok KEY VALUE" or "error: reason". The file keeps
the ID the servo was launched with; a servo moved by `kmx set-id` answers at
another, so an ID here is the one the servo answers at now: every socket is
asked ("id", answered "ok id N") and the one at that ID gets the event. A
real bus has no such thing: the servo's own sensors see the real supply and
heat.

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
        """The socket servo-bus made for the servo it launched as dev_id."""
        return os.path.join(self.dir, "servo-%d.sock" % dev_id)

    def sockets(self):
        """The inject sockets' file names (servo-LAUNCH_ID.sock)."""
        try:
            names = os.listdir(self.dir)
        except OSError:
            return []
        return sorted(n for n in names if n.startswith("servo-") and n.endswith(".sock") and n[6:-5].isdigit())

    def live_ids(self, timeout=5.0):
        """Socket file name -> the ID its servo answers at now (host-sim answers
        "id" with 0x0F in force, which `kmx set-id` changes while the socket
        keeps its launch name). Asked of all at once, again every 0.2 s until
        each answered or `timeout` s passed: a socket still silent then (its
        servo gone) is left out."""
        names, ids = self.sockets(), {}
        end = time.monotonic() + timeout
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
            s.bind("")  # an address of our own (Linux autobind): host-sim answers to it
            while len(ids) < len(names) and time.monotonic() < end:
                for name in names:
                    if name not in ids:
                        try:
                            s.sendto(b"id", os.path.join(self.dir, name))
                        except (ConnectionRefusedError, FileNotFoundError):
                            pass  # a restarting servo binds its socket again
                self._collect_ids(s, ids, min(time.monotonic() + 0.2, end))
        return ids

    @staticmethod
    def _collect_ids(s, ids, until):
        """Answers "ok id N" into ids (by the sender's file name) until `until`."""
        while time.monotonic() < until:
            s.settimeout(max(0.01, until - time.monotonic()))
            try:
                data, sender = s.recvfrom(256)
            except socket.timeout:
                return
            words = data.decode(errors="replace").split()
            if len(words) == 3 and words[:2] == ["ok", "id"] and words[2].isdigit() and sender:
                ids[os.path.basename(sender)] = int(words[2])

    def servos(self):
        """The IDs the bench's servos answer at now (each once)."""
        return sorted(set(self.live_ids().values()))

    def inject(self, dev_id, key, value, timeout=5.0):
        """Sends "KEY VALUE" to the plant of the servo answering at dev_id now;
        its answer ("ok ..."). Raises KmxError in words: a key or value the
        bench does not take, no servo with a bench at dev_id, two of them
        there, or no answer within `timeout` s (a restarting servo binds its
        socket again: retried until then)."""
        if key not in KEYS:
            raise KmxError("bench: no key %r (%s)" % (key, ", ".join(KEYS)))
        what, unit, lo, hi = KEYS[key]
        if not isinstance(value, int) or not lo <= value <= hi:
            raise KmxError("bench: %s (%s) takes %d..%d %s, not %r" % (key, what, lo, hi, unit, value))
        return self._send(self.resolve(dev_id, timeout), ("%s %d" % (key, value)).encode(), timeout)

    def resolve(self, dev_id, timeout=5.0):
        """The socket of the one servo with a bench that answers at dev_id now."""
        ids = self.live_ids(timeout)
        at = [name for name, live in sorted(ids.items()) if live == dev_id]
        if len(at) > 1:
            raise KmxError("bench: %d servos with a bench answer at ID %d: separate them first "
                           "(kmx scan names the command)" % (len(at), dev_id))
        if not at:
            silent = [n for n in self.sockets() if n not in ids]
            raise KmxError("bench: no servo with a bench answers at ID %d now (%s%s)" % (
                dev_id, "the bench's servos are at ID " + ", ".join(map(str, sorted(set(ids.values()))))
                if ids else "no bench socket in " + self.dir,
                "; no answer from " + ", ".join(silent) if silent else ""))
        return os.path.join(self.dir, at[0])

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
