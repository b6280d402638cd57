# SPDX-License-Identifier: Apache-2.0
"""The host package host/kmx: the frame codec against the worked frames of
docs/protocol.md §2 byte for byte, the stream parser on noise and checksum
errors, registers by name with units and range refusal (from
docs/registers.json), transport spec parsing and each open error's
message, and the Bus against a real host-sim servo over TCP and over a
pseudo-terminal, and on the 3-servo host-sim bus of sim/bus/servo-bus
(super-ID and 0x82 answers collected). The host-sim image is the host-sim preset's
(build/host-sim, or KM_BUILD_HOST_SIM); a missing image fails with the
command that builds it. About 8 s."""
import os
import re
import socket
import subprocess
import sys
import tempfile
import time
import unittest
from unittest import mock

from kmx import deps, faultlog
from kmx import frame as fr
from kmx import transport as tp
from kmx import bus as bus_mod
from kmx.bus import Bus
from kmx.errors import (ConnectionRefused, KmxError, MissingPackage, NoAnswer,
                        NoSuchDevice, NotASerialPort, PortBusy, RangeError, RegisterError,
                        SpecError, TransportError)
from kmx.registers import RegisterMap, Registers

REPO = os.path.realpath(os.path.join(os.path.dirname(__file__), "..", ".."))


def h(s):
    return bytes.fromhex(s)


class WorkedFrames(unittest.TestCase):
    """docs/protocol.md §2 worked frames, each copied from the table."""

    def test_ping_and_short_response(self):
        self.assertEqual(fr.ping(1), h("F9 FF 01 02 01 FB"))
        self.assertEqual(fr.encode_status(1, 0), h("F9 F5 01 02 00 FC"))

    def test_reads_and_answer(self):
        self.assertEqual(fr.read(1, 0x0B), h("F9 FF 01 03 02 0B EE"))
        self.assertEqual(fr.read(1, 0x01), h("F9 FF 01 03 02 01 F8"))
        self.assertEqual(fr.encode_response(1, fr.READ, 0x01, b"\x00\x05"), h("F9 F5 01 05 02 01 00 05 F1"))

    def test_writes_and_restart(self):
        self.assertEqual(fr.write(1, 0x65, h("84 03 E8 03")), h("F9 FF 01 07 03 65 84 03 E8 03 1D"))
        self.assertEqual(fr.restart(1), h("F9 FF 01 07 03 02 E1 E2 E3 E4 68"))

    def test_multi_id_write(self):
        self.assertEqual(fr.multi_write(0x64, [(1, b"\x02"), (2, b"\x02"), (3, b"\x02")]),
                         h("F9 FF FE 0A 83 64 01 01 02 02 02 03 02 03"))
        self.assertEqual(fr.multi_write(0x65, [(5, h("00 00 E8 03")), (7, h("5A 00 E8 03")), (9, h("A6 FF E8 03"))]),
                         h("F9 FF FE 13 83 65 04 05 00 00 E8 03 07 5A 00 E8 03 09 A6 FF E8 03 2D"))
        self.assertEqual(fr.multi_write(0x65, [(5, h("00 00")), (7, h("5A 00")), (9, h("A6 FF"))]),
                         h("F9 FF FE 0D 83 65 02 05 00 00 07 5A 00 09 A6 FF F6"))

    def test_multi_id_write_refuses_uneven_or_empty(self):
        for bad in ([], [(1, b"\x01"), (2, b"\x01\x02")], [(1, b"")], [(251, b"\x01")]):
            with self.assertRaises(ValueError):
                fr.multi_write(0x64, bad)

    def test_sync_write_and_execute(self):
        for dev_id, cs in ((1, 0x90), (2, 0x8F), (3, 0x8E)):
            self.assertEqual(fr.sync_write(dev_id, 0x64, b"\x02"), bytes([0xF9, 0xFF, dev_id, 0x04, 0x04, 0x64, 0x02, cs]))
        self.assertEqual(fr.sync_execute(), h("F9 FF FE 02 84 7B"))
        self.assertEqual(fr.sync_write(5, 0x65, h("00 00 E8 03")), h("F9 FF 05 07 04 65 00 00 E8 03 9F"))
        self.assertEqual(fr.sync_write(7, 0x65, h("5A 00 E8 03")), h("F9 FF 07 07 04 65 5A 00 E8 03 43"))
        self.assertEqual(fr.sync_write(9, 0x65, h("A6 FF E8 03")), h("F9 FF 09 07 04 65 A6 FF E8 03 F6"))

    def test_multi_id_read_frame(self):
        # F9 FF FE len 82 addr id1..idn chk; chk = ~(FE+06+82+46+01+02+03) = ~0x1D2 -> 2D
        self.assertEqual(fr.multi_read(0x46, [1, 2, 3]), h("F9 FF FE 06 82 46 01 02 03 2D"))
        for bad in ([], [1, 1], [251]):
            with self.assertRaises(ValueError):
                fr.multi_read(0x46, bad)

    def test_address_rule_and_constants(self):
        with self.assertRaises(ValueError):
            fr.encode_command(1, fr.PING, 0x01)
        with self.assertRaises(ValueError):
            fr.encode_command(1, fr.READ)
        self.assertEqual((fr.ID_SUPER, fr.ID_BROADCAST, fr.ID_MAX), (0xFD, 0xFE, 250))

    def test_status_words(self):
        self.assertEqual(fr.status_words(0), ["ok"])
        self.assertEqual(fr.status_words(0x41), ["command failed", "voltage protection"])


class AnswerSlots(unittest.TestCase):
    """docs/protocol-decisions.md "Super-ID answer slots": the Bus listens
    until the last slot's answer has ended at the bus baud."""

    def test_worked_table(self):
        self.assertEqual(bus_mod.slot_us(6, 115200), 695)    # ping
        self.assertEqual(bus_mod.slot_us(11, 115200), 1129)  # read 0x46
        self.assertAlmostEqual(bus_mod.slots_window_s(4, 6, 115200), (200 + 3 * 695 + 6 * 10e6 / 115200) / 1e6)

    def test_scan_window_follows_the_baud(self):
        self.assertAlmostEqual(bus_mod.slots_window_s(251, 6, 115200), 0.1745, places=4)
        self.assertGreater(bus_mod.slots_window_s(251, 6, 9600), 2.0)  # 12 x longer: 0.5 s would miss IDs > 60
        self.assertLess(bus_mod.slots_window_s(251, 6, 1000000), 0.025)


class ExtensionFrames(unittest.TestCase):
    """Our extension read 0x7F (docs/protocol-decisions.md): frame and fault-log entry layout."""

    def test_ext_read_frame(self):
        self.assertEqual(fr.ext_read(1, 0x12), h("F9 FF 01 03 7F 12 6A"))  # the document's example

    def test_fault_log_entry(self):
        e = faultlog.Entry(h("C5 02 00 00 02 02 00 00 E8 1C 9C FF FA 00 60 01 00 00"))
        self.assertEqual((e.ms, e.kind_text, e.bits_text, e.boots_ago), (709, "released by itself", "current", 0))
        self.assertEqual(e.row(0), [0, "this", 709, "released by itself", "current", "7.400 V", "-100 mA",
                                    "25.0 °C", "35.2 °"])
        hw = faultlog.Entry(h("01 00 00 00 04 21 01 00 00 00 00 00 00 00 00 00 00 00"))
        self.assertEqual((hw.kind_text, hw.bits_text, hw.row(0)[1]),
                         ("hardware faults found", "position sensor, crystal", "-1"))
        with self.assertRaises(ValueError):
            faultlog.Entry(b"\x00" * 17)


class StreamParser(unittest.TestCase):
    ANSWER = h("F9 F5 01 05 02 01 00 05 F1")

    def test_byte_by_byte(self):
        p = fr.Parser()
        got = []
        for b in self.ANSWER * 2:
            got += p.feed(bytes([b]))
        self.assertEqual([f.to_bytes() for f in got], [self.ANSWER] * 2)
        self.assertEqual((got[0].cmd, got[0].addr, got[0].params), (fr.READ, 0x01, b"\x00\x05"))

    def test_resync_on_noise(self):
        p = fr.Parser()
        got = p.feed(h("00 F9 13 F5 F9") + self.ANSWER + h("FF F9") + fr.encode_status(2, 0x40))
        self.assertEqual([f.id for f in got], [1, 2])
        self.assertEqual(got[1].status, 0x40)
        self.assertEqual(p.checksum_errors, 0)
        self.assertEqual(p.noise_bytes, 7)

    def test_checksum_error_reported_and_next_frame_kept(self):
        bad = bytearray(self.ANSWER)
        bad[-1] ^= 0xFF
        p = fr.Parser()
        got = p.feed(bytes(bad) + fr.encode_status(3, 0))
        self.assertEqual([f.id for f in got], [3])
        self.assertEqual(p.checksum_errors, 1)

    def test_length_error(self):
        p = fr.Parser()
        got = p.feed(h("F9 F5 01 01 00") + fr.encode_status(4, 0))
        self.assertEqual([f.id for f in got], [4])
        self.assertEqual(p.length_errors, 1)

    def test_both_headers(self):
        p = fr.Parser(headers=(fr.RSP_HEADER, fr.CMD_HEADER))
        got = p.feed(fr.ping(1) + fr.encode_status(1, 0))
        self.assertEqual([(f.is_command, f.id) for f in got], [(True, 1), (False, 1)])


class RegisterDescription(unittest.TestCase):
    """docs/registers.json, generated by km_regdoc --json (docs/protocol.md §5)."""

    @classmethod
    def setUpClass(cls):
        cls.m = RegisterMap.load()

    def test_lookup(self):
        self.assertEqual(self.m["position"].address, 0x46)
        self.assertIs(self.m["POSITION"], self.m[0x46])
        self.assertIs(self.m["0x4B"], self.m["voltage"])
        self.assertIs(self.m["torque-switch"], self.m["torque_switch"])
        with self.assertRaisesRegex(RegisterError, "no register named 'posiiton'; did you mean position"):
            self.m["posiiton"]
        with self.assertRaisesRegex(RegisterError, r"no register at address 0x20 \(reserved\)"):
            self.m[0x20]

    def test_every_register_has_units_and_description(self):
        self.assertGreaterEqual(len(self.m), 40)
        for r in self.m:
            self.assertTrue(r.title and r.description, r.name)
            self.assertTrue(re.fullmatch(r"[a-z][a-z0-9_]*", r.name), r.name)
            for f in r.fields:
                self.assertIn("unit", f)
                self.assertGreater(f["scale"], 0)

    def test_decode_with_units(self):
        self.assertEqual(str(self.m["voltage"].decode(h("E8 1C"))), "7.400 V")
        self.assertAlmostEqual(self.m["voltage"].decode(h("E8 1C")).value, 7.4)
        self.assertEqual(str(self.m["position"].decode((450).to_bytes(2, "little"))), "45.0 °")
        self.assertEqual(str(self.m["position"].decode((-40000).to_bytes(4, "little", signed=True))), "-4000.0 °")
        self.assertEqual(str(self.m["temp_limits"].decode(h("3C 05"))), "60 °C, 5 °C")
        self.assertEqual(str(self.m["current_limit"].decode(h("E8 03 14"))), "1000 mA, 2.0 s")
        self.assertEqual(str(self.m["baud"].decode(h("80 04"))), "115200 baud")
        self.assertEqual(str(self.m["status"].decode(h("41 07"))),
                         "0x41 (command failed, voltage protection), random 0x07")
        self.assertEqual(str(self.m["protocol_version"].decode(h("00 00 02 05"))), "0x05020000")
        self.assertEqual(str(self.m["product_info"].decode(b"KM-SIM-P135")), "KM-SIM-P135")
        with self.assertRaisesRegex(RangeError, "voltage .0x4B.: answer of 3 bytes, expected 2"):
            self.m["voltage"].decode(b"\x00\x00\x00")

    def test_encode_from_units(self):
        self.assertEqual(self.m["move_time"].encode("90, 1000"), h("84 03 E8 03"))  # §2 worked frame
        self.assertEqual(self.m["move_time"].encode("90 °, 1000 ms"), h("84 03 E8 03"))
        self.assertEqual(self.m["move_time"].encode(-9), h("A6 FF"))
        self.assertEqual(self.m["baud"].encode(115200), h("80 04"))
        self.assertEqual(self.m["angle_min"].encode("-135.0 °"), (-1350).to_bytes(2, "little", signed=True))
        self.assertEqual(self.m["temp_limits"].encode([70, 5]), h("46 05"))
        self.assertEqual(self.m["config"].encode("0x08"), h("08"))
        self.assertEqual(self.m["position"].encode(4000), (40000).to_bytes(4, "little", signed=True))

    def test_refusals_before_sending(self):
        cases = [("torque_switch", 4, RangeError, "torque_switch: 4 is outside 0..3"),
                 ("baud", 115250, RangeError, "not a multiple of 100 baud"),
                 ("zero_increment", 10.5, RangeError, r"10.5 ° is outside -10.0 °..10.0 °"),
                 ("temp_limits", "60", RangeError, r"takes 2 values \(u8, u8\), got 1"),
                 ("move_time", "1, 2, 3", RangeError, "takes 1 or 2 values"),
                 ("id", 251, RangeError, "id: 251 is outside 0..250$"),
                 ("response_delay", -1, RangeError, "outside 0 µs..65535 µs"),
                 ("position", "far", RangeError, "'far' is not a number"),
                 ("firmware_version", 1, RegisterError, r"firmware_version \(0x0C\) is read-only")]
        for name, value, exc, msg in cases:
            with self.subTest(name=name), self.assertRaisesRegex(exc, msg):
                self.m[name].encode(value)

    def test_bad_values_refused_with_a_kmx_error(self):
        """Every bad input has a defined outcome: a KmxError, never another exception."""
        junk = ["", "x", "1 2 3 4 5", "0x", "1e9", "-1e9", "nan", "inf", "-inf", [], ["1"] * 6, 1.5, -1,
                float("nan"), float("inf"), "45 °", "°", None, True, "E1 E2 E3", b"\x01"]
        for reg in self.m:
            for v in junk:
                with self.subTest(reg=reg.name, value=v):
                    try:
                        out = reg.encode(v)
                    except KmxError:
                        continue
                    self.assertIn(len(out), reg.lengths)
            for data in (b"", b"\x00" * 30, b"\x01", b"\x00" * 5):
                with self.subTest(reg=reg.name, data=data):
                    try:
                        reg.decode(data)
                    except KmxError:
                        pass
        with self.assertRaisesRegex(RangeError, "position: nan is not a finite number"):
            self.m["position"].encode("nan")
        with self.assertRaisesRegex(RangeError, r"restart: takes exactly 4 bytes in hex \(E1 E2 E3 E4\)"):
            self.m["restart"].encode("E1 E2")
        self.assertEqual(self.m["restart"].encode(["E1", "E2", "E3", "E4"]), fr.RESTART_MAGIC)

    def test_product_bound_left_to_the_servo(self):
        self.assertEqual(self.m["max_current"].fields[0]["max"], "product")
        self.assertEqual(self.m["max_current"].encode(5000), (5000).to_bytes(2, "little"))

    def test_get_of_write_only_refused_without_bus(self):
        with self.assertRaisesRegex(RegisterError, r"move_time \(0x65\) is write-only"):
            Registers(None, self.m).get(1, "move_time")


class TransportSpecs(unittest.TestCase):
    def test_good_specs(self):
        self.assertEqual(tp.parse_spec("tcp:127.0.0.1:7000"), ("tcp", {"host": "127.0.0.1", "port": 7000}))
        self.assertEqual(tp.parse_spec("serial:/dev/ttyUSB0@1000000"), ("serial", {"path": "/dev/ttyUSB0", "baud": 1000000}))
        self.assertEqual(tp.parse_spec("serial:/dev/ttyUSB0"), ("serial", {"path": "/dev/ttyUSB0", "baud": 115200}))
        self.assertEqual(tp.parse_spec("pty:/dev/pts/4"), ("pty", {"path": "/dev/pts/4"}))

    def test_bad_specs(self):
        cases = [("localhost", "expected tcp:HOST:PORT, serial:/dev/ttyUSB0@115200, pty:/dev/pts/N or rfc2217:HOST:PORT@115200"),
                 ("tcp:7000", "tcp wants HOST:PORT"),
                 ("tcp:127.0.0.1:", "port must be a number in 1..65535"),
                 ("tcp:127.0.0.1:99999", "port must be a number in 1..65535"),
                 ("serial:@115200", "serial wants a device path"),
                 ("serial:/dev/ttyUSB0@fast", "baud after @ must be a positive number"),
                 ("pty:", "pty wants a path"),
                 ("usb:/dev/x", "unknown transport 'usb'")]
        for spec, msg in cases:
            with self.subTest(spec=spec), self.assertRaises(SpecError) as cm:
                tp.open_transport(spec)
            self.assertIn(msg, str(cm.exception))
            self.assertIn(spec, str(cm.exception))

    def test_connection_refused(self):
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        s.close()  # nothing listens there now
        with self.assertRaisesRegex(ConnectionRefused, "tcp:127.0.0.1:%d: connection refused" % port):
            tp.open_transport("tcp:127.0.0.1:%d" % port)

    def test_no_such_device(self):
        with self.assertRaisesRegex(NoSuchDevice, "no such device /nonexistent/ttyUSB9"):
            tp.open_transport("serial:/nonexistent/ttyUSB9@115200")
        with self.assertRaisesRegex(NoSuchDevice, "no such device /dev/pts/9999"):
            tp.open_transport("pty:/dev/pts/9999")

    def test_not_a_serial_port(self):
        with self.assertRaisesRegex(NotASerialPort, "/dev/null is not a serial port"):
            tp.open_transport("serial:/dev/null")
        with tempfile.NamedTemporaryFile() as f:
            with self.assertRaisesRegex(NotASerialPort, "is not a serial port .not a character device"):
                tp.open_transport("serial:%s@9600" % f.name)

    def test_missing_pyserial_names_the_package(self):
        with mock.patch.dict(sys.modules, {"serial": None}), \
                mock.patch.object(deps, "DEBIAN_DIST_PACKAGES", "/nonexistent"):
            with self.assertRaisesRegex(MissingPackage, "^kmx opens every bus through pyserial: apt-get install "
                                                        r"python3-serial \(and run with /usr/bin/python3\), or "
                                                        r"pip install pyserial$"):
                tp.open_transport("serial:/dev/ttyUSB0@115200")

    def test_every_error_is_a_kmx_error(self):
        for cls in (SpecError, ConnectionRefused, NoSuchDevice, NotASerialPort, PortBusy, MissingPackage,
                    NoAnswer, RangeError, RegisterError):
            self.assertTrue(issubclass(cls, KmxError))


def host_sim_image():
    build = os.environ.get("KM_BUILD_HOST_SIM", os.path.join(REPO, "build", "host-sim"))
    image = os.path.join(build, "boards", "host-sim", "km-servo-host-sim")
    if not os.access(image, os.X_OK):
        raise AssertionError("no host-sim image at %s: build it with "
                             "cmake --preset host-sim && cmake --build --preset host-sim" % image)
    return image


class HostSim:
    """One real host-sim servo (the firmware as a native program) on a fresh
    flash file, over TCP (--listen) or a pseudo-terminal (--pty)."""

    def __init__(self, pty=False, extra=()):
        self.dir = tempfile.TemporaryDirectory()
        argv = [host_sim_image(), "--flash", os.path.join(self.dir.name, "servo.flash"), "--gap-floor-us", "0",
                *extra]
        if pty:
            self.proc = subprocess.Popen(argv + ["--pty"], stdout=subprocess.PIPE, text=True)
            line = self.proc.stdout.readline().split()
            assert line[:1] == ["pty"], line
            self.spec = "pty:" + line[1]
        else:  # a port it binds itself, said on stdout once it listens
            self.proc = subprocess.Popen(argv + ["--listen", "127.0.0.1:0"], stdout=subprocess.PIPE, text=True)
            line = self.proc.stdout.readline().split()
            assert line[:1] == ["port"], line
            self.spec = "tcp:127.0.0.1:" + line[1]

    def close(self):
        self.proc.kill()
        self.proc.wait()
        if self.proc.stdout:
            self.proc.stdout.close()
        self.dir.cleanup()


class EchoWire:
    """A half-duplex adapter in front of the real transport: every byte the
    master writes comes back in its own receive stream, as on a one-wire bus."""

    def __init__(self, inner):
        self.inner = inner
        self.echo = b""

    def write(self, data):
        self.inner.write(data)
        self.echo += bytes(data)

    def read(self, timeout):
        if self.echo:
            data, self.echo = self.echo, b""
            return data
        return self.inner.read(timeout)

    def flush_input(self):
        self.inner.flush_input()

    def close(self):
        self.inner.close()


class NoisyWire(EchoWire):
    """A wire that corrupts the checksum byte of every 6-byte short
    response the servo sends (counted over the stream, however it is cut
    into chunks): every ping answer fails its checksum."""

    def __init__(self, inner):
        super().__init__(inner)
        self.offset = 0

    def read(self, timeout):
        data = bytearray(self.inner.read(timeout))
        for i in range(len(data)):
            if (self.offset + i) % 6 == 5:
                data[i] ^= 0x5A
        self.offset += len(data)
        return bytes(data)


class BusOverTcp(unittest.TestCase):
    """Bus against host-sim over TCP: docs/protocol.md §3 commands, §1 super ID."""

    def setUp(self):
        self.sim = HostSim()
        self.addCleanup(self.sim.close)
        self.bus = Bus(self.sim.spec)
        self.addCleanup(self.bus.close)
        self.regs = Registers(self.bus)

    def test_ping_read_by_name(self):
        t0 = time.monotonic()
        self.assertEqual(self.bus.ping(0), 0)  # a fresh servo: ID 0, status clear
        f = self.bus.read_frame(0, 0x0B)
        self.assertGreater(f.time, t0)
        self.assertEqual(f.params, h("00 00 02 05"))
        self.assertEqual(str(self.regs.get(0, "protocol_version")), "0x05020000")
        self.assertEqual(str(self.regs.get(0, "voltage")), "7.400 V")  # host-sim's supply
        self.assertEqual(str(self.regs.get(0, "baud")), "115200 baud")

    def test_set_by_name_and_move(self):
        self.regs.set(0, "response_delay", "350 µs")
        self.assertEqual(str(self.regs.get(0, "response_delay")), "350 µs")
        self.regs.set(0, "torque_switch", 2)
        self.regs.set(0, "move_time", "45, 300")
        deadline = time.monotonic() + 3
        while time.monotonic() < deadline:
            pos = self.regs.get(0, "position").value
            if abs(pos - 45.0) <= 0.5:
                break
            time.sleep(0.05)
        self.assertAlmostEqual(pos, 45.0, delta=0.5)

    def test_refused_write_sends_nothing(self):
        with self.assertRaises(RangeError):
            self.regs.set(0, "torque_switch", 9)
        self.assertEqual(self.bus.transactions, 0)

    def test_id_change_scan_restart(self):
        self.regs.set(0, "id", 7)
        self.assertEqual(self.bus.scan(timeout=0.3), [(7, 0)])
        boot = self.bus.restart(7)
        self.assertLess(boot, 3.0)
        self.assertEqual(self.bus.ping(7), 0)  # the ID persisted (§5.1 P)

    def test_no_answer_after_retries(self):
        t0 = time.monotonic()
        with self.assertRaisesRegex(NoAnswer, r"ping ID 9: no answer from ID 9 within 100 ms \(3 tries\)"):
            self.bus.ping(9)
        self.assertGreaterEqual(time.monotonic() - t0, 0.3)

    def test_sync_write_then_execute(self):
        self.bus.sync_write(0, 0x64, b"\x02")
        self.bus.sync_write(0, 0x64, b"\x00")  # §3: a second 0x04 replaces the buffer
        self.bus.execute()
        self.assertEqual(str(self.regs.get(0, "torque_switch")), "0")
        self.bus.sync_write(0, 0x64, b"\x02")
        self.assertEqual(self.bus.read(0, 0x64), b"\x00")  # §3: a command to this servo clears the buffer
        self.bus.execute()
        self.assertEqual(self.bus.read(0, 0x64), b"\x00")

    def test_multi_read_one_servo(self):
        self.assertEqual(self.bus.multi_read(0x4B, [3, 0]), {3: None, 0: h("E8 1C")})

    def test_multi_write(self):
        self.bus.multi_write(0x64, {0: b"\x02"})
        self.assertEqual(self.bus.read(0, 0x64), b"\x02")

    def test_echo_of_own_commands_ignored(self):
        bus = Bus(EchoWire(self.bus.transport))
        self.assertEqual(bus.ping(0), 0)
        self.assertEqual(bus.read(0, 0x0F), b"\x00")
        self.assertEqual(bus.scan(timeout=0.3), [(0, 0)])
        self.assertEqual((bus.echoes, bus.foreign_commands, bus.checksum_errors), (3, 0, 0))

    def test_servo_gone(self):
        self.assertEqual(self.bus.ping(0), 0)
        self.sim.proc.kill()
        self.sim.proc.wait()
        with self.assertRaisesRegex(TransportError, "^%s: the bus closed the connection$" % re.escape(self.sim.spec)):
            self.bus.ping(0)

    def test_checksum_errors_reported(self):
        bus = Bus(NoisyWire(self.bus.transport))
        with self.assertRaisesRegex(NoAnswer, r"ping ID 0: no answer from ID 0 within 100 ms \(3 tries\); "
                                              r"3 checksum errors heard"):
            bus.ping(0)

    def test_raw_bytes_bad_checksum_gets_no_answer(self):
        bad = bytearray(fr.ping(0))
        bad[-1] ^= 0x55
        self.bus.send_bytes(bad)
        self.assertEqual(self.bus.listen(0.2), [])  # §4: a bad checksum gets no answer
        st = self.bus.ping(0)
        self.assertTrue(st & 0x20, "bit 5 for the frame with our ID and a bad checksum (§4)")


class ServoBus:
    """Three real host-sim servos, IDs 1, 2, 3, on the emulated wire of
    sim/bus/servo-bus (answers reach the master in wire order)."""

    def __init__(self, ids=(1, 2, 3), extra=()):
        host_sim_image()
        self.proc = subprocess.Popen(
            [sys.executable, os.path.join(REPO, "sim", "bus", "servo-bus"), "--ids", ",".join(map(str, ids)),
             "--port", "0", "--backend", "host-sim", "--gap-floor-us", "0", *extra],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        line = self.proc.stdout.readline().split()
        if line[:1] != ["ready"]:
            self.close()
            raise AssertionError("servo-bus did not start: %r" % line)
        self.spec = "tcp:" + line[1]
        self.rfc2217 = "rfc2217:%s@115200" % line[1]

    def close(self):
        self.proc.terminate()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.proc.stdout.close()


class BusOnThreeServos(unittest.TestCase):
    """The Bus's collection of super-ID answers (docs/protocol.md §1, §3) and of
    multi-ID read 0x82 answers (docs/protocol-decisions.md), multi-ID write
    0x83 and sync write 0x04/0x84 across servos, on the 3-servo host-sim
    bus. The slot order itself is the firmware's and the emulated wire's
    (tests/bus, the conformance suite, run alone); with the host's cores
    shared, host-sim answers can swap slots, so these tests check that every
    answer is collected, mapped to its ID and returned in arrival order."""

    @classmethod
    def setUpClass(cls):
        cls.wire = ServoBus()
        cls.bus = Bus(cls.wire.spec)

    @classmethod
    def tearDownClass(cls):
        cls.bus.close()
        cls.wire.close()

    def test_scan_collects_every_answer(self):
        self.assertAlmostEqual(self.bus.scan_window(), 0.1745 + 0.1, places=3)  # 115200 on the emulated bus
        frames = self.bus.scan_frames()
        self.assertEqual(sorted((f.id, f.status) for f in frames), [(1, 0), (2, 0), (3, 0)])
        self.assertEqual([f.time for f in frames], sorted(f.time for f in frames))  # arrival order
        self.assertTrue(all(f.time > self.bus.sent_at for f in frames))

    def test_multi_read_collects_every_answer(self):
        frames = self.bus.multi_read_frames(fr.REG_ID, [3, 1, 2])
        self.assertEqual(sorted((f.id, f.params) for f in frames), [(1, b"\x01"), (2, b"\x02"), (3, b"\x03")])
        self.assertEqual([f.time for f in frames], sorted(f.time for f in frames))
        self.assertEqual(self.bus.multi_read(0x0B, [2, 7, 1]),
                         {2: h("00 00 02 05"), 7: None, 1: h("00 00 02 05")})

    def test_multi_write_then_multi_read(self):
        self.bus.multi_write(0x64, {1: b"\x02", 2: b"\x01", 3: b"\x00"})
        self.assertEqual(self.bus.multi_read(0x64, [1, 2, 3]), {1: b"\x02", 2: b"\x01", 3: b"\x00"})

    def test_sync_write_interleaved_then_execute(self):
        for dev_id, v in ((1, 0), (2, 1), (3, 2)):  # §3: frames for other IDs keep each buffer
            self.bus.sync_write(dev_id, 0x64, bytes([v]))
        self.bus.execute()
        self.assertEqual(self.bus.multi_read(0x64, [1, 2, 3]), {1: b"\x00", 2: b"\x01", 3: b"\x02"})


class BusOverPty(unittest.TestCase):
    """The same servo program behind a pseudo-terminal, through pyserial."""

    def setUp(self):
        self.sim = HostSim(pty=True)
        self.addCleanup(self.sim.close)

    def test_ping_read_scan(self):
        with Bus(self.sim.spec) as bus:
            self.assertEqual(bus.ping(0), 0)
            self.assertEqual(str(Registers(bus).get(0, "product_info")), "KM-SIM-P135")
            self.assertEqual(bus.scan(timeout=0.3), [(0, 0)])

    def test_servo_gone(self):
        """The servo program ends (its pty closes): a TransportError, not pyserial's termios.error."""
        with Bus(self.sim.spec) as bus:
            self.assertEqual(bus.ping(0), 0)
            self.sim.proc.kill()
            self.sim.proc.wait()
            with self.assertRaisesRegex(TransportError, "^%s: .*(gone|failed)" % re.escape(self.sim.spec)):
                bus.ping(0)

    def test_busy_port(self):
        with Bus(self.sim.spec):
            with self.assertRaisesRegex(PortBusy, "is busy: another program holds it"):
                tp.open_transport(self.sim.spec)


if __name__ == "__main__":
    unittest.main()
