#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Open a bus and find every servo on it (super-ID ping, docs/protocol.md §1),
then read what each one is.    python3 host/examples/scan.py [--bus SPEC]"""
from _bus import bus_spec

import kmx

with kmx.open_bus(bus_spec()) as bus:
    found = bus.scan()  # [(id, status byte)] in the order they answered
    print("%d servos on %s" % (len(found), bus.transport.spec))
    for dev_id, status in found:
        servo = kmx.Servo(bus, dev_id)
        print("ID %d: %s, firmware %s, %s, status: %s" % (
            dev_id, servo["product_info"], servo["firmware_version"], servo["voltage"],
            ", ".join(kmx.frame.status_words(status))))
