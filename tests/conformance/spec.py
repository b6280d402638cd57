# SPDX-License-Identifier: Apache-2.0
"""The suite's oracle: docs/protocol.md §4 and §5 written out as data.

Typed by hand from docs/protocol.md (never from the firmware's
tables or docs/registers.*): address, name, access, the answer lengths a read
may give, signedness, the default where the spec gives one (None where it
says "—", product-dependent) and whether it is persisted user data.
"""

# §4 status byte
BIT_RUNNING = 0x80
BIT_FAILED = 0x40      # bit 6: last command failed (bad value)
BIT_EXCEPTION = 0x20   # bit 5: checksum error, command/address not supported
BIT_HW = 0x10
BITS_56 = BIT_FAILED | BIT_EXCEPTION

ID_MAX = 250
ID_SUPER = 0xFD
ID_BROADCAST = 0xFE
INVALID_IDS = (251, 252, 255)  # §1 Reading
RESTART_MAGIC = bytes([0xE1, 0xE2, 0xE3, 0xE4])
PROTOCOL_VERSION = 0x05020000
BAUD_DEFAULT = 1152  # /100

# §3: 0x83 addresses, and the size k of one entry's data per address
# (0x64 u8; 0x65/0x66 i16 [, u16]; 0x68/0x6E/0x6F i16)
MULTI_WRITE_ADDRS = (0x64, 0x65, 0x66, 0x68, 0x6E, 0x6F)


class Reg:
    def __init__(self, addr, name, access, lengths, signed=False, default=None,
                 persisted=False, fields=None):
        self.addr = addr
        self.name = name
        self.access = access          # "R", "W", "RW"
        self.lengths = lengths        # answer (read) or value (write) lengths allowed
        self.signed = signed
        self.default = default        # int, tuple of field values, or None ("—")
        self.persisted = persisted
        self.fields = fields          # struct-like sizes of a multi-field value, e.g. (2, 1)

    @property
    def readable(self):
        return "R" in self.access

    @property
    def writable(self):
        return "W" in self.access


# §5.1 .. §5.4. 0x46 is "R (W)": readable; a write zeroes it on motor
# products only, so it is not in the writable set the suite checks.
REGISTERS = [
    Reg(0x01, "servo status", "R", [2], fields=(1, 1)),
    Reg(0x02, "system restart", "W", [4]),
    Reg(0x03, "user data reset", "W", [1]),
    Reg(0x0A, "product information", "R", list(range(1, 17))),  # Decision: ASCII, up to 16 B
    Reg(0x0B, "protocol version", "R", [4], default=PROTOCOL_VERSION),
    Reg(0x0C, "firmware version", "R", [4]),
    Reg(0x0F, "servo ID", "RW", [1], default=0, persisted=True),
    Reg(0x10, "baud rate / 100", "RW", [2], default=BAUD_DEFAULT, persisted=True),
    Reg(0x11, "system configuration", "RW", [1], default=0x02, persisted=True),
    Reg(0x12, "response delay", "RW", [2], default=200, persisted=True),
    Reg(0x13, "maximum output torque", "RW", [2], default=1000, persisted=True),
    Reg(0x14, "maximum output current", "RW", [2], persisted=True),
    Reg(0x15, "maximum rotation speed", "RW", [2], persisted=True),
    Reg(0x16, "level-1 zero offset", "R", [2], signed=True, persisted=True),
    Reg(0x17, "level-2 zero offset", "RW", [2], signed=True, default=0, persisted=True),
    Reg(0x18, "level-2 zero offset increment", "W", [1], signed=True),
    Reg(0x19, "minimum angle limit", "RW", [2], signed=True, persisted=True),
    Reg(0x1A, "maximum angle limit", "RW", [2], signed=True, persisted=True),
    Reg(0x32, "protection enable", "RW", [1], default=0x0F, persisted=True),
    Reg(0x33, "protection release mode", "RW", [1], default=0x00, persisted=True),
    Reg(0x34, "state while protecting", "RW", [1], default=0x54, persisted=True),
    Reg(0x35, "hardware fault flags", "R", [1], default=0),
    Reg(0x36, "protection flags", "RW", [1], default=0),
    Reg(0x3C, "voltage thresholds", "RW", [2], persisted=True, fields=(1, 1)),
    Reg(0x3D, "temperature thresholds", "RW", [2], default=(60, 5), persisted=True, fields=(1, 1)),
    Reg(0x3E, "current threshold", "RW", [3], default=(None, 20), persisted=True, fields=(2, 1)),
    Reg(0x3F, "stall threshold", "RW", [3], default=(600, 20), persisted=True, fields=(2, 1)),
    Reg(0x46, "current position", "R", [2, 4], signed=True),
    Reg(0x47, "current speed", "R", [2], signed=True),
    Reg(0x48, "current", "R", [2], signed=True),
    Reg(0x49, "output PWM", "R", [2], signed=True),
    Reg(0x4A, "temperature", "R", [2], signed=True),
    Reg(0x4B, "voltage", "R", [2], signed=True),
    Reg(0x4C, "position deviation", "R", [2, 4], signed=True),
    Reg(0x4D, "rotation time", "R", [4]),
    Reg(0x5A, "control mode", "RW", [1], default=0),
    Reg(0x5B, "torque limit", "RW", [2]),   # default = 0x13
    Reg(0x5C, "current limit", "RW", [2]),  # default = 0x14
    Reg(0x5D, "speed limit", "RW", [2]),    # default = 0x15
    Reg(0x64, "torque switch", "RW", [1], default=3),
    Reg(0x65, "move in time", "W", [2, 4]),
    Reg(0x66, "move at speed", "W", [2, 4]),
    Reg(0x67, "servo advanced", "W", [5]),
    Reg(0x68, "interpolation target", "W", [2]),
    Reg(0x6E, "motor constant torque", "W", [2]),
    Reg(0x6F, "motor constant speed", "W", [2]),
    Reg(0x70, "motor advanced", "W", [5]),
]
BY_ADDR = {r.addr: r for r in REGISTERS}
# 0x5B..0x5D follow 0x13..0x15 (§5.4 "=0x13")
FOLLOWS = {0x5B: 0x13, 0x5C: 0x14, 0x5D: 0x15}
# §5: address ranges not in the map are "reserve": unsupported
RESERVED = [a for a in range(256) if a not in BY_ADDR]
# Registers that keep their value across a user-data reset of level 1 (§5.1 0x03)
KEPT_BY_LEVEL1 = (0x0F, 0x10, 0x16, 0x17)
PERSISTED_RW = [r.addr for r in REGISTERS if r.persisted and r.writable]


def to_int(raw, signed=False):
    return int.from_bytes(raw, "little", signed=signed)


def u8(v):
    return bytes([v & 0xFF])


def u16(v):
    return (v & 0xFFFF).to_bytes(2, "little")


def i16(v):
    return v.to_bytes(2, "little", signed=True)
