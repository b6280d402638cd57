# SPDX-License-Identifier: Apache-2.0
"""One servo on a bus, its registers by name with units (docs/python-api.md).

    import kmx
    with kmx.open_bus("tcp:127.0.0.1:7000") as bus:
        servo = kmx.Servo(bus, 1)
        servo.get("voltage")            # Value: 7.400 V (.value 7.4, .raw [7400])
        servo["position"]               # the same as get("position")
        servo.set("max_speed", 360)     # checked (type, range, product) before sending
        servo.torque("on")
        servo.move(45, time_ms=500)     # 0x65; speed_dps=... for 0x66
        servo.wait()                    # until §4 bit 7 (moving) clears
        servo.fault_log()               # [faultlog.Entry], newest first
"""

import time

from . import faultlog
from . import frame as fr
from .bus import Bus
from .errors import KmxError, RangeError
from .registers import Registers

TORQUE = {"off": 0, "brake": 1, "on": 2}  # §5.4 0x64
MOVING = 0x80  # §4 bit 7: executing a rotation command


def open_bus(spec, timeout=0.1, retries=2):
    """A Bus on the transport spec names (kmx.transport: tcp:HOST:PORT, a
    device path, rfc2217://, socket://, loop://, spy://, hwgrep://)."""
    return Bus(spec, timeout=timeout, retries=retries)


class Servo:
    """The servo at `dev_id` on `bus`: registers by name with units, moves,
    the fault log. Every failure is a KmxError (kmx.errors)."""

    def __init__(self, bus, dev_id, registers=None):
        self.bus, self.id = bus, dev_id
        self.registers = registers or Registers(bus)

    def __repr__(self):
        return "<Servo ID %d on %s>" % (self.id, self.bus.transport.spec)

    def get(self, name):
        """A register by name or address: a Value (str() with units, .value in units, .raw)."""
        return self.registers.get(self.id, name)

    __getitem__ = get

    def set(self, name, value, check=True):
        """Writes a register by name, value in its units; refused (RangeError,
        nothing sent) when the type, range, the product's bound or, for a
        move, the angle limits do not allow it. Returns the status byte the
        servo answers a ping with afterwards (§4: bit 6 = refused)."""
        self.registers.set(self.id, name, value, check=check)
        return self.bus.ping(self.id)

    def status(self):
        """The status byte (§4) and its words."""
        code = self.bus.ping(self.id)
        return code, fr.status_words(code)

    def torque(self, state):
        """Torque "on" (hold), "off" (free) or "brake" (0x64)."""
        if state not in TORQUE:
            raise RangeError("torque: '%s' is not one of %s" % (state, ", ".join(TORQUE)))
        return self.set("torque_switch", TORQUE[state])

    def move(self, angle, time_ms=None, speed_dps=None):
        """Moves to angle (degrees): in time_ms (0x65), at speed_dps (0x66),
        or as fast as allowed (0x65 without a time)."""
        if speed_dps is not None:
            return self.set("move_speed", [angle, speed_dps])
        return self.set("move_time", [angle] if time_ms is None else [angle, time_ms])

    def moving(self):
        """True while the servo executes a rotation command (§4 bit 7)."""
        return bool(self.bus.read(self.id, fr.REG_STATUS)[0] & MOVING)

    def wait(self, timeout_s=10.0, poll_s=0.02):
        """Waits until the move ends; returns the position (degrees). KmxError after timeout_s."""
        deadline = time.monotonic() + timeout_s
        while self.moving():
            if time.monotonic() > deadline:
                raise KmxError("ID %d: still moving after %.1f s (at %s)" % (self.id, timeout_s, self["position"]))
            time.sleep(poll_s)
        return self["position"].value

    def fault_log(self):
        """The fault log (extension 0x7F, docs/protocol-decisions.md): entries, newest first."""
        _events, held, _kept = faultlog.read_summary(self.bus, self.id)
        return faultlog.read_entries(self.bus, self.id, held)
