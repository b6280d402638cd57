#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Many servos at once, by register name: one multi-ID read (0x82) for a
register of all of them, one multi-ID write (0x83) giving each its own
target, and a sync write (0x04 to each, then one 0x84) that makes them act
together.    python3 host/examples/group.py [--bus SPEC]"""
import time

from _bus import bus_spec

import kmx

with kmx.open_bus(bus_spec()) as bus:
    regs = kmx.Registers(bus)
    ids = sorted(i for i, _ in bus.scan())
    print("voltage of %s in one 0x82 frame:" % ids, {i: str(v) for i, v in regs.get_many(ids, "voltage").items()})
    regs.set_many("torque_switch", {i: 2 for i in ids})  # 0x83: torque on, each its own value
    regs.set_many("move_time", {i: [10.0 * n, 300] for n, i in enumerate(ids, 1)})  # each its target
    time.sleep(0.6)
    print("positions:", {i: str(v) for i, v in regs.get_many(ids, "position").items()})
    regs.sync_set("move_speed", {i: [0, 180] for i in ids})  # 0x04 each, then 0x84: all start together
    for i in ids:
        kmx.Servo(bus, i, regs).wait()
    print("back at:", {i: str(v) for i, v in regs.get_many(ids, "position").items()})
    regs.set_many("torque_switch", {i: 0 for i in ids})
