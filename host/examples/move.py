#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Torque on, a move in a given time, wait until it ends, a move at a given
speed, and a target outside the angle limits named before it is sent.
    python3 host/examples/move.py [--bus SPEC]"""
from _bus import bus_spec

import kmx
from kmx.errors import RangeError

with kmx.open_bus(bus_spec()) as bus:
    servo = kmx.Servo(bus, 1)
    servo.torque("on")
    servo.move(45, time_ms=500)
    print("arrived at %.1f °" % servo.wait())
    servo.move(-30, speed_dps=180)
    print("arrived at %.1f °" % servo.wait())
    try:
        servo.move(170)
    except RangeError as e:
        print("refused: %s" % e)
    servo.move(0, time_ms=300)
    servo.wait()
    servo.torque("off")
