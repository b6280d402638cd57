#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The fault log (extension 0x7F) and the errors kmx raises: a servo that
does not answer, an unknown register, a value out of range, a bus that is
not there. Every one is a KmxError with a one-line message.
    python3 host/examples/faults.py [--bus SPEC]"""
from _bus import bus_spec

import kmx
from kmx.errors import KmxError, NoAnswer, RangeError, RegisterError, TransportError

with kmx.open_bus(bus_spec()) as bus:
    servo = kmx.Servo(bus, 1)
    entries = servo.fault_log()
    print("fault log of ID 1: %d entries" % len(entries))
    for e in entries:
        print("  %s: %s at %.3f V, %.1f °C" % (e.kind_text, e.bits_text, e.supply_mv / 1000, e.temp_dc / 10))
    for what, call, error in (("ID 99", lambda: kmx.Servo(bus, 99)["voltage"], NoAnswer),
                              ("a misspelt name", lambda: servo["voltgae"], RegisterError),
                              ("a negative speed", lambda: servo.set("max_speed", -5), RangeError)):
        try:
            call()
        except error as e:
            print("%s: %s: %s" % (what, type(e).__name__, e))
try:
    kmx.open_bus("tcp:127.0.0.1:1")
except TransportError as e:
    print("no bus: %s" % e)
except KmxError as e:  # the base class catches every one of them
    print("other: %s" % e)
