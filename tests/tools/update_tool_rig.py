# SPDX-License-Identifier: Apache-2.0
"""What the update tools' tests share (test_servo_update.py, test_kmx_update.py):
update images made in the test, the tool run as a process (a traceback
fails the test), a folder with a good image for the refusals, and two
host-sim servos (applications without a bootloader) that must be left
untouched."""
import os
import struct
import subprocess
import tempfile
import zlib

from kmx.bus import Bus  # noqa: E402
from test_kmx import ServoBus  # noqa: E402

APP_VERSION = 0x00100100  # what host-sim's 0x0C reads: bootloader byte 0, application v1


def make_image(body_len=1024, model=0x4B4D0001, version=0x00100102):
    """An update image as tools/gen/make-image writes one (docs/update.md §2):
    the 32-byte header, FF to 0x100, then the body."""
    length = 0x100 + body_len
    body = bytes((7 * i) & 0xFF for i in range(body_len))
    rest = b"\xff" * (0x100 - 32) + body  # bytes [32, length)
    head = struct.pack("<IIIIII", 0x57464D4B, model, length, version, 0x100, 0x4000)
    head += struct.pack("<I", zlib.crc32(rest) & 0xFFFFFFFF)
    head += struct.pack("<I", zlib.crc32(head) & 0xFFFFFFFF)
    return head + rest


def run_tool(tool, *args):
    """tool ARGS as a process; a traceback fails the test."""
    r = subprocess.run([tool, *args], capture_output=True, text=True, timeout=120)
    if "Traceback" in r.stderr:
        raise AssertionError("%s %s printed a traceback:\n%s"
                             % (os.path.basename(tool), " ".join(args), r.stderr))
    return r


class ImageDir:
    """Mixin for a TestCase: a temporary folder per test with a good image in it (self.good)."""

    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.addCleanup(self.dir.cleanup)
        self.good = self.file("good.kmfw", make_image())

    def file(self, name, data):
        """Writes `data` to a file of the folder; its path."""
        path = os.path.join(self.dir.name, name)
        with open(path, "wb") as f:
            f.write(data)
        return path


class AppServos:
    """Mixin for a TestCase: two host-sim servos, applications without a bootloader, and an image
    (self.image) an update tool must refuse to send them."""

    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory()
        cls.image = os.path.join(cls.dir.name, "v2.kmfw")
        with open(cls.image, "wb") as f:
            f.write(make_image())
        cls.wire = ServoBus(ids=(1, 2))

    @classmethod
    def tearDownClass(cls):
        cls.wire.close()
        cls.dir.cleanup()

    def untouched(self, update_state=False):
        """Both servos answer with status 0 and still report their 0x0C
        (update_state: and 0x78 STATUS says application)."""
        with Bus(self.wire.spec) as bus:
            for i in (1, 2):
                self.assertEqual(bus.ping(i), 0, "ID %d" % i)
                self.assertEqual(bus.read(i, 0x0C), struct.pack("<I", APP_VERSION))
                if update_state:
                    self.assertEqual(bus.update_state(i), 0, "ID %d: 0x78 STATUS says application" % i)
