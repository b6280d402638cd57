#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""A stand-in for the host-sim servo program, for testing sim/bus/servo-bus
without QEMU or the firmware. It speaks the host-sim command-line contract:

    fake_servo.py --listen 127.0.0.1:PORT --flash FILE [--baud N] [--report-baud]

listens on PORT for one bus connection at a time (PORT 0: one the kernel
picks, printed "port N" on stdout), keeps its ID in FILE
(blank or missing file = fresh servo = ID 0), and answers per docs/protocol.md
§2/§3: ping (own ID or super ID), read of 0x01 (status, random) and 0x0F (ID),
write of 0x0F (ID; no answer at response level 0). Frames with a bad checksum
are ignored. Test knobs, from the environment:
    FAKE_SERVO_LOG_DIR   write id<ID>.pid (pid) and rx-<pid>.bin (bytes heard)
    FAKE_SERVO_EXIT      "ID:SECONDS:CODE": once its ID is ID, exit with CODE
                         after SECONDS
    FAKE_SERVO_BOOT_DELAY  seconds to wait before listening (slow boot)
"""
import argparse
import os
import random
import socket
import threading
import time

from kmx import frame as kmframe  # noqa: E402  (docs/architecture.md "The folders": PYTHONPATH)

SLOT_S = 0.002  # super-ID answer slot per ID (the fake's own, simplified rule)


class FakeServo:
    def __init__(self, flash):
        self.flash = flash
        self.id = 0
        try:
            with open(flash, "rb") as f:
                first = f.read(1)
            if first and first[0] <= kmframe.ID_MAX:
                self.id = first[0]
        except FileNotFoundError:
            with open(flash, "wb") as f:
                f.write(b"\xFF" * 4096)  # erased NOR
        self.log_dir = os.environ.get("FAKE_SERVO_LOG_DIR")
        self.exit_rule = os.environ.get("FAKE_SERVO_EXIT")
        self.on_id_change()

    def on_id_change(self):
        if self.log_dir:
            with open(os.path.join(self.log_dir, "id%d.pid" % self.id), "w") as f:
                f.write(str(os.getpid()))
        if self.exit_rule:
            want, secs, code = self.exit_rule.split(":")
            if int(want) == self.id:
                t = threading.Timer(float(secs), os._exit, args=(int(code),))
                t.daemon = True
                t.start()

    def set_id(self, new_id):
        with open(self.flash, "r+b") as f:
            f.write(bytes([new_id]))
        self.id = new_id
        self.on_id_change()

    def handle(self, frame):
        """Return the answer bytes for one command frame (b"" = silence)."""
        mine = frame.id == self.id
        to_super = frame.id == kmframe.ID_SUPER
        broadcast = frame.id == kmframe.ID_BROADCAST
        if frame.cmd == kmframe.PING and (mine or to_super):
            if to_super:
                time.sleep(self.id * SLOT_S)
            return kmframe.encode_status(self.id, 0)
        if frame.cmd == kmframe.READ and (mine or to_super):
            if frame.addr == kmframe.REG_ID:
                return kmframe.encode_response(self.id, kmframe.READ, kmframe.REG_ID, bytes([self.id]))
            if frame.addr == kmframe.REG_STATUS:
                return kmframe.encode_response(self.id, kmframe.READ, kmframe.REG_STATUS,
                                             bytes([0, random.randrange(256)]))
            return kmframe.encode_status(self.id, 0x20)  # address not supported
        if frame.cmd == kmframe.WRITE and (mine or broadcast):
            if frame.addr == kmframe.REG_ID and len(frame.params) == 1 and \
                    frame.params[0] <= kmframe.ID_MAX:
                self.set_id(frame.params[0])  # response level 0: no answer
        return b""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--listen", required=True)
    ap.add_argument("--flash", required=True)
    ap.add_argument("--baud", type=int, default=115200)
    ap.add_argument("--report-baud", action="store_true")  # servo-bus: "baud N" on stdout
    args = ap.parse_args()
    host, port = args.listen.rsplit(":", 1)
    servo = FakeServo(args.flash)
    time.sleep(float(os.environ.get("FAKE_SERVO_BOOT_DELAY", "0")))
    srv = socket.socket()
    srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    srv.bind((host, int(port)))
    srv.listen(1)
    if int(port) == 0:  # the host-sim contract: the port chosen, on stdout
        print("port %d" % srv.getsockname()[1], flush=True)
    if args.report_baud:
        print("baud %d" % args.baud, flush=True)
    rx_log = None
    if servo.log_dir:
        rx_log = open(os.path.join(servo.log_dir, "rx-%d.bin" % os.getpid()), "ab", buffering=0)
    while True:
        conn, _ = srv.accept()
        parser = kmframe.Parser(kmframe.CMD_HEADER)
        while True:
            data = conn.recv(4096)
            if not data:
                break
            if rx_log:
                rx_log.write(data)
            for frame in parser.feed(data):
                answer = servo.handle(frame)
                if answer:
                    conn.sendall(answer)
        conn.close()


if __name__ == "__main__":
    main()
