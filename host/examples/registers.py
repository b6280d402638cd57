#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Registers by name with units: read, write, read back, and a value the
servo's product does not allow, refused before anything is sent.
    python3 host/examples/registers.py [--bus SPEC]"""
from _bus import bus_spec

import kmx
from kmx.errors import RangeError

with kmx.open_bus(bus_spec()) as bus:
    servo = kmx.Servo(bus, 1)
    speed = servo.get("max_speed")  # a Value: str() has the unit, .value is the number
    print("max_speed is %s (the number: %r)" % (speed, speed.value))
    servo.set("max_speed", 300)
    print("after set: %s" % servo["max_speed"])
    try:
        servo.set("max_speed", 5000)
    except RangeError as e:  # the product's bound, named; no frame went out
        print("refused: %s" % e)
    servo.set("max_speed", speed.value)  # put it back (0x15 is stored user data)
    print("restored: %s" % servo["max_speed"])
