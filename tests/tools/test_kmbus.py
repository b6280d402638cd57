# SPDX-License-Identifier: Apache-2.0
"""kmbus.py against the worked frames of docs/protocol.md §2, and the stream parser
against split, corrupted and interleaved input."""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "tools"))
import kmbus  # noqa: E402


def h(s):
    return bytes.fromhex(s)


class WorkedFrames(unittest.TestCase):
    """Each expected frame is copied from the §2 table."""

    def test_ping(self):
        self.assertEqual(kmbus.ping(1), h("F9 FF 01 02 01 FB"))

    def test_short_response(self):
        self.assertEqual(kmbus.encode_status(1, 0), h("F9 F5 01 02 00 FC"))

    def test_reads(self):
        self.assertEqual(kmbus.read(1, 0x0B), h("F9 FF 01 03 02 0B EE"))
        self.assertEqual(kmbus.read(1, 0x01), h("F9 FF 01 03 02 01 F8"))

    def test_read_status_response(self):
        self.assertEqual(kmbus.encode_response(1, kmbus.READ, 0x01, b"\x00\x05"),
                         h("F9 F5 01 05 02 01 00 05 F1"))

    def test_writes(self):
        self.assertEqual(kmbus.write(1, 0x65, h("84 03 E8 03")),
                         h("F9 FF 01 07 03 65 84 03 E8 03 1D"))
        self.assertEqual(kmbus.write(1, 0x02, h("E1 E2 E3 E4")),
                         h("F9 FF 01 07 03 02 E1 E2 E3 E4 68"))

    def test_multi_id_writes(self):
        self.assertEqual(
            kmbus.encode_command(kmbus.ID_BROADCAST, kmbus.MULTI_WRITE, 0x64,
                                 h("01 01 02 02 02 03 02")),
            h("F9 FF FE 0A 83 64 01 01 02 02 02 03 02 03"))
        self.assertEqual(
            kmbus.encode_command(kmbus.ID_BROADCAST, kmbus.MULTI_WRITE, 0x65,
                                 h("04 05 00 00 E8 03 07 5A 00 E8 03 09 A6 FF E8 03")),
            h("F9 FF FE 13 83 65 04 05 00 00 E8 03 07 5A 00 E8 03 09 A6 FF E8 03 2D"))
        self.assertEqual(
            kmbus.encode_command(kmbus.ID_BROADCAST, kmbus.MULTI_WRITE, 0x65,
                                 h("02 05 00 00 07 5A 00 09 A6 FF")),
            h("F9 FF FE 0D 83 65 02 05 00 00 07 5A 00 09 A6 FF F6"))

    def test_sync_writes(self):
        for dev_id, cs in ((1, 0x90), (2, 0x8F), (3, 0x8E)):
            self.assertEqual(kmbus.encode_command(dev_id, kmbus.SYNC_WRITE, 0x64, b"\x02"),
                             bytes([0xF9, 0xFF, dev_id, 0x04, 0x04, 0x64, 0x02, cs]))
        self.assertEqual(kmbus.encode_command(kmbus.ID_BROADCAST, kmbus.SYNC_EXECUTE),
                         h("F9 FF FE 02 84 7B"))
        self.assertEqual(kmbus.encode_command(5, kmbus.SYNC_WRITE, 0x65, h("00 00 E8 03")),
                         h("F9 FF 05 07 04 65 00 00 E8 03 9F"))
        self.assertEqual(kmbus.encode_command(7, kmbus.SYNC_WRITE, 0x65, h("5A 00 E8 03")),
                         h("F9 FF 07 07 04 65 5A 00 E8 03 43"))
        self.assertEqual(kmbus.encode_command(9, kmbus.SYNC_WRITE, 0x65, h("A6 FF E8 03")),
                         h("F9 FF 09 07 04 65 A6 FF E8 03 F6"))

    def test_write_id_frame_from_brief(self):
        # F9 FF 00 04 03 0F id cs
        f = kmbus.write(0, kmbus.REG_ID, b"\x07")
        self.assertEqual(f[:7], h("F9 FF 00 04 03 0F 07"))
        self.assertEqual(f[7], ~(0x00 + 0x04 + 0x03 + 0x0F + 0x07) & 0xFF)

    def test_address_rules(self):
        with self.assertRaises(ValueError):
            kmbus.encode_command(1, kmbus.PING, 0x01)
        with self.assertRaises(ValueError):
            kmbus.encode_command(1, kmbus.READ)
        with self.assertRaises(ValueError):
            kmbus.encode_command(1, kmbus.WRITE, 0x10, bytes(251))


class StreamParser(unittest.TestCase):
    def test_parses_worked_responses(self):
        p = kmbus.Parser()
        frames = p.feed(h("F9 F5 01 02 00 FC F9 F5 01 05 02 01 00 05 F1"))
        self.assertEqual(len(frames), 2)
        self.assertTrue(frames[0].is_status)
        self.assertEqual((frames[0].id, frames[0].status), (1, 0))
        self.assertEqual((frames[1].cmd, frames[1].addr, frames[1].params),
                         (kmbus.READ, 0x01, b"\x00\x05"))

    def test_byte_by_byte_and_garbage(self):
        p = kmbus.Parser()
        stream = h("00 F9 13 F9") + kmbus.encode_status(7, 0x40) + h("F9") + \
            kmbus.encode_response(7, 2, 0x0F, b"\x07")
        got = []
        for b in stream:
            got += p.feed(bytes([b]))
        self.assertEqual([(f.id, f.body) for f in got],
                         [(7, b"\x40"), (7, h("02 0F 07"))])

    def test_bad_checksum_dropped_then_resync(self):
        p = kmbus.Parser()
        bad = bytearray(kmbus.encode_status(3, 0))
        bad[-1] ^= 1
        got = p.feed(bytes(bad) + kmbus.encode_status(4, 0))
        self.assertEqual([f.id for f in got], [4])
        self.assertEqual(p.bad_frames, 1)

    def test_command_parser_and_roundtrip(self):
        p = kmbus.Parser(kmbus.CMD_HEADER)
        frames = [kmbus.ping(1), kmbus.read(1, 0x0B), kmbus.write(2, 0x0F, b"\x05"),
                  kmbus.encode_command(kmbus.ID_BROADCAST, kmbus.SYNC_EXECUTE)]
        got = p.feed(b"".join(frames))
        self.assertEqual([f.to_bytes() for f in got], frames)
        self.assertEqual((got[0].cmd, got[0].addr), (kmbus.PING, None))
        self.assertEqual((got[2].addr, got[2].params), (0x0F, b"\x05"))
        # a response parser ignores command frames (the master's own bytes)
        self.assertEqual(kmbus.Parser().feed(b"".join(frames)), [])


if __name__ == "__main__":
    unittest.main()
