# SPDX-License-Identifier: Apache-2.0
"""Our extension reads (command 0x7F, docs/protocol-decisions.md "Extension
command 0x7F"): where the user data came from at boot, why the MCU last
reset, and the fault log (the last 16 protection and self-test events,
newest first), decoded into words and units."""

import struct

from .errors import BadAnswer

EXT_BOOT_SOURCE = 0x01
EXT_RESET_CAUSE = 0x02
EXT_BAUD_IN_FORCE = 0x03
EXT_LOG_SUMMARY = 0x10
EXT_LOG_ENTRY = 0x11  # + n, n = 0 the newest
LOG_LENGTH = 16

BOOT_SOURCES = {
    0: "loaded from flash",
    1: "loaded from flash, registers new to this firmware at defaults",
    2: "product defaults: flash erased (first boot)",
    3: "product defaults: no valid record in flash",
    4: "product defaults: stored layout from another firmware version",
    5: "store unusable: product defaults, commits fail",
}
RESET_CAUSES = {0: "power-on", 1: "reset pin", 2: "software (0x02 restart)", 3: "watchdog",
                4: "fault (HardFault)", 5: "brown-out", 6: "other"}
KINDS = {0: "empty", 1: "tripped", 2: "released by itself", 3: "released by 0x36", 4: "hardware faults found"}
PROTECTION_BITS = ((0x08, "stall"), (0x04, "temperature"), (0x02, "current"), (0x01, "voltage"))  # 0x36
HW_FAULT_BITS = ((0x80, "other"), (0x40, "motor"), (0x20, "position sensor"), (0x10, "current sensor"),
                 (0x08, "voltage sensor"), (0x04, "temperature sensor"), (0x02, "memory"), (0x01, "crystal"))


class Entry:
    """One 18-byte fault-log entry (little-endian)."""

    def __init__(self, data):
        if len(data) != 18:
            raise ValueError("a fault-log entry is 18 bytes, got %d" % len(data))
        (self.ms, self.kind, self.bits, self.boots_ago, _pad, self.supply_mv, self.current_ma,
         self.temp_dc, self.position_dd) = struct.unpack("<IBBBBHhhi", bytes(data))

    @property
    def kind_text(self):
        return KINDS.get(self.kind, "kind %d" % self.kind)

    @property
    def bits_text(self):
        table = HW_FAULT_BITS if self.kind == 4 else PROTECTION_BITS
        words = [name for bit, name in table if self.bits & bit]
        return ", ".join(words) if words else "-"

    def row(self, index):
        return [index, "this" if self.boots_ago == 0 else "-%d" % self.boots_ago, self.ms, self.kind_text,
                self.bits_text, "%.3f V" % (self.supply_mv / 1000), "%d mA" % self.current_ma,
                "%.1f °C" % (self.temp_dc / 10), "%.1f °" % (self.position_dd / 10)]


ROW_HEADER = ["#", "boot", "t_ms", "event", "what", "supply", "current", "temperature", "position"]


def read_summary(bus, dev_id):
    """(events ever recorded, entries held, of them from before the last reset)."""
    data = bus.ext_read(dev_id, EXT_LOG_SUMMARY)
    if len(data) != 7:
        raise BadAnswer("ID %d: fault-log summary of %d bytes, expected 7" % (dev_id, len(data)))
    events, held, kept, _length = struct.unpack("<IBBB", data)
    return events, held, kept


def read_entries(bus, dev_id, held):
    return [Entry(bus.ext_read(dev_id, EXT_LOG_ENTRY + n)) for n in range(min(held, LOG_LENGTH))]


def read_boot(bus, dev_id):
    """(where the user data came from, why the MCU last reset), in words."""
    src = bus.ext_read(dev_id, EXT_BOOT_SOURCE)[0]
    cause = bus.ext_read(dev_id, EXT_RESET_CAUSE)[0]
    return BOOT_SOURCES.get(src, "source %d" % src), RESET_CAUSES.get(cause, "cause %d" % cause)
