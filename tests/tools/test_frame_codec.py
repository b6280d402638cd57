# SPDX-License-Identifier: Apache-2.0
"""kmx.frame (host/kmx/frame.py) against the worked frames of docs/protocol.md §2, and the stream parser
against split, corrupted and interleaved input."""
import unittest

from kmx import frame as kmframe  # noqa: E402  (docs/architecture.md "The folders": PYTHONPATH)


def h(s):
    return bytes.fromhex(s)


class WorkedFrames(unittest.TestCase):
    """Each expected frame is copied from the §2 table."""

    def test_ping(self):
        self.assertEqual(kmframe.ping(1), h("F9 FF 01 02 01 FB"))

    def test_short_response(self):
        self.assertEqual(kmframe.encode_status(1, 0), h("F9 F5 01 02 00 FC"))

    def test_reads(self):
        self.assertEqual(kmframe.read(1, 0x0B), h("F9 FF 01 03 02 0B EE"))
        self.assertEqual(kmframe.read(1, 0x01), h("F9 FF 01 03 02 01 F8"))

    def test_read_status_response(self):
        self.assertEqual(kmframe.encode_response(1, kmframe.READ, 0x01, b"\x00\x05"),
                         h("F9 F5 01 05 02 01 00 05 F1"))

    def test_writes(self):
        self.assertEqual(kmframe.write(1, 0x65, h("84 03 E8 03")),
                         h("F9 FF 01 07 03 65 84 03 E8 03 1D"))
        self.assertEqual(kmframe.write(1, 0x02, h("E1 E2 E3 E4")),
                         h("F9 FF 01 07 03 02 E1 E2 E3 E4 68"))

    def test_multi_id_writes(self):
        self.assertEqual(
            kmframe.encode_command(kmframe.ID_BROADCAST, kmframe.MULTI_WRITE, 0x64,
                                 h("01 01 02 02 02 03 02")),
            h("F9 FF FE 0A 83 64 01 01 02 02 02 03 02 03"))
        self.assertEqual(
            kmframe.encode_command(kmframe.ID_BROADCAST, kmframe.MULTI_WRITE, 0x65,
                                 h("04 05 00 00 E8 03 07 5A 00 E8 03 09 A6 FF E8 03")),
            h("F9 FF FE 13 83 65 04 05 00 00 E8 03 07 5A 00 E8 03 09 A6 FF E8 03 2D"))
        self.assertEqual(
            kmframe.encode_command(kmframe.ID_BROADCAST, kmframe.MULTI_WRITE, 0x65,
                                 h("02 05 00 00 07 5A 00 09 A6 FF")),
            h("F9 FF FE 0D 83 65 02 05 00 00 07 5A 00 09 A6 FF F6"))

    def test_sync_writes(self):
        for dev_id, cs in ((1, 0x90), (2, 0x8F), (3, 0x8E)):
            self.assertEqual(kmframe.encode_command(dev_id, kmframe.SYNC_WRITE, 0x64, b"\x02"),
                             bytes([0xF9, 0xFF, dev_id, 0x04, 0x04, 0x64, 0x02, cs]))
        self.assertEqual(kmframe.encode_command(kmframe.ID_BROADCAST, kmframe.SYNC_EXECUTE),
                         h("F9 FF FE 02 84 7B"))
        self.assertEqual(kmframe.encode_command(5, kmframe.SYNC_WRITE, 0x65, h("00 00 E8 03")),
                         h("F9 FF 05 07 04 65 00 00 E8 03 9F"))
        self.assertEqual(kmframe.encode_command(7, kmframe.SYNC_WRITE, 0x65, h("5A 00 E8 03")),
                         h("F9 FF 07 07 04 65 5A 00 E8 03 43"))
        self.assertEqual(kmframe.encode_command(9, kmframe.SYNC_WRITE, 0x65, h("A6 FF E8 03")),
                         h("F9 FF 09 07 04 65 A6 FF E8 03 F6"))

    def test_write_id_frame_from_brief(self):
        # F9 FF 00 04 03 0F id cs
        f = kmframe.write(0, kmframe.REG_ID, b"\x07")
        self.assertEqual(f[:7], h("F9 FF 00 04 03 0F 07"))
        self.assertEqual(f[7], ~(0x00 + 0x04 + 0x03 + 0x0F + 0x07) & 0xFF)

    def test_address_rules(self):
        with self.assertRaises(ValueError):
            kmframe.encode_command(1, kmframe.PING, 0x01)
        with self.assertRaises(ValueError):
            kmframe.encode_command(1, kmframe.READ)
        with self.assertRaises(ValueError):
            kmframe.encode_command(1, kmframe.WRITE, 0x10, bytes(251))


class StreamParser(unittest.TestCase):
    def test_parses_worked_responses(self):
        p = kmframe.Parser()
        frames = p.feed(h("F9 F5 01 02 00 FC F9 F5 01 05 02 01 00 05 F1"))
        self.assertEqual(len(frames), 2)
        self.assertTrue(frames[0].is_status)
        self.assertEqual((frames[0].id, frames[0].status), (1, 0))
        self.assertEqual((frames[1].cmd, frames[1].addr, frames[1].params),
                         (kmframe.READ, 0x01, b"\x00\x05"))

    def test_byte_by_byte_and_garbage(self):
        p = kmframe.Parser()
        stream = h("00 F9 13 F9") + kmframe.encode_status(7, 0x40) + h("F9") + \
            kmframe.encode_response(7, 2, 0x0F, b"\x07")
        got = []
        for b in stream:
            got += p.feed(bytes([b]))
        self.assertEqual([(f.id, f.body) for f in got],
                         [(7, b"\x40"), (7, h("02 0F 07"))])

    def test_bad_checksum_dropped_then_resync(self):
        p = kmframe.Parser()
        bad = bytearray(kmframe.encode_status(3, 0))
        bad[-1] ^= 1
        got = p.feed(bytes(bad) + kmframe.encode_status(4, 0))
        self.assertEqual([f.id for f in got], [4])
        self.assertEqual(p.bad_frames, 1)

    def test_command_parser_and_roundtrip(self):
        p = kmframe.Parser(kmframe.CMD_HEADER)
        frames = [kmframe.ping(1), kmframe.read(1, 0x0B), kmframe.write(2, 0x0F, b"\x05"),
                  kmframe.encode_command(kmframe.ID_BROADCAST, kmframe.SYNC_EXECUTE)]
        got = p.feed(b"".join(frames))
        self.assertEqual([f.to_bytes() for f in got], frames)
        self.assertEqual((got[0].cmd, got[0].addr), (kmframe.PING, None))
        self.assertEqual((got[2].addr, got[2].params), (0x0F, b"\x05"))
        # a response parser ignores command frames (the master's own bytes)
        self.assertEqual(kmframe.Parser().feed(b"".join(frames)), [])


if __name__ == "__main__":
    unittest.main()
