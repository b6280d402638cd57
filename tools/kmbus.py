"""KINGMAX serial servo frames (PROTOCOL.md §2, §3): checksum, command and
response encoders, and a stream parser. Python 3 standard library only; shared
by the bus launcher (tools/servo-bus), the bus master and the test doubles.

Frame layout: header(2) id length body checksum, where body is
  command frame  (F9 FF): command [address] parameters
  response frame (F9 F5): command address value-bytes, or one status byte
length = len(body) + 1 (the checksum), checksum = ~(id + length + sum(body)) & 0xFF.
"""

CMD_HEADER = b"\xF9\xFF"
RSP_HEADER = b"\xF9\xF5"

ID_MAX = 250
ID_SUPER = 0xFD
ID_BROADCAST = 0xFE

PING = 0x01
READ = 0x02
WRITE = 0x03
SYNC_WRITE = 0x04
MULTI_READ = 0x82
MULTI_WRITE = 0x83
SYNC_EXECUTE = 0x84
NO_ADDRESS = (PING, SYNC_EXECUTE)  # commands without an address byte (§2)

REG_STATUS = 0x01
REG_ID = 0x0F
REG_BAUD = 0x10

LENGTH_MAX = 252  # a whole frame is at most 256 bytes


def checksum(data):
    """~(sum of bytes from ID through the last parameter) & 0xFF."""
    return ~sum(data) & 0xFF


def _frame(header, dev_id, body):
    body = bytes(body)
    if not 0 <= dev_id <= 0xFF:
        raise ValueError("id out of range: %r" % dev_id)
    length = len(body) + 1
    if length < 2 or length > LENGTH_MAX:
        raise ValueError("body of %d bytes does not fit a frame" % len(body))
    core = bytes([dev_id, length]) + body
    return header + core + bytes([checksum(core)])


def encode_command(dev_id, cmd, addr=None, params=b""):
    """Command frame F9 FF. addr must be None exactly for ping and sync execute."""
    if (addr is None) != (cmd in NO_ADDRESS):
        raise ValueError("command 0x%02X %s an address" %
                         (cmd, "takes no" if cmd in NO_ADDRESS else "needs"))
    body = bytes([cmd]) + (b"" if addr is None else bytes([addr])) + bytes(params)
    return _frame(CMD_HEADER, dev_id, body)


def ping(dev_id):
    return encode_command(dev_id, PING)


def read(dev_id, addr):
    return encode_command(dev_id, READ, addr)


def write(dev_id, addr, value):
    return encode_command(dev_id, WRITE, addr, value)


def encode_response(dev_id, cmd, addr, value=b""):
    """Response frame F9 F5 (e.g. the answer to a read)."""
    return _frame(RSP_HEADER, dev_id, bytes([cmd, addr]) + bytes(value))


def encode_status(dev_id, status):
    """Short response frame: F9 F5 id 02 status checksum."""
    return _frame(RSP_HEADER, dev_id, bytes([status]))


class Frame:
    """One checked frame. body is everything between length and checksum."""

    def __init__(self, header, dev_id, body):
        self.header = bytes(header)
        self.id = dev_id
        self.body = bytes(body)

    @property
    def is_response(self):
        return self.header == RSP_HEADER

    @property
    def is_status(self):
        """A short response: its body is one status byte."""
        return self.is_response and len(self.body) == 1

    @property
    def status(self):
        return self.body[0] if self.is_status else None

    @property
    def cmd(self):
        return None if self.is_status else self.body[0]

    @property
    def addr(self):
        if self.is_status or (not self.is_response and self.cmd in NO_ADDRESS):
            return None
        return self.body[1] if len(self.body) > 1 else None

    @property
    def params(self):
        if self.is_status:
            return b""
        skip = 1 if (not self.is_response and self.cmd in NO_ADDRESS) else 2
        return self.body[skip:]

    def to_bytes(self):
        return _frame(self.header, self.id, self.body)

    def __eq__(self, other):
        return (isinstance(other, Frame) and self.header == other.header and
                self.id == other.id and self.body == other.body)

    def __repr__(self):
        return "Frame(%s id=%d body=%s)" % (self.header.hex(), self.id, self.body.hex())


class Parser:
    """Byte-stream parser for one header (responses by default). feed() takes
    any chunk of bytes and returns the complete, checksum-valid frames in it;
    partial frames wait for the next chunk. On a bad checksum or length it
    skips one byte and hunts for the next header, counting the drop."""

    def __init__(self, header=RSP_HEADER):
        self.header = bytes(header)
        self.buf = bytearray()
        self.bad_frames = 0

    def feed(self, data):
        self.buf += data
        out = []
        while True:
            start = self.buf.find(self.header)
            if start < 0:
                # keep a trailing first header byte: the second may follow
                keep = 1 if self.buf[-1:] == self.header[:1] else 0
                del self.buf[:len(self.buf) - keep]
                return out
            del self.buf[:start]
            if len(self.buf) < 4:
                return out
            length = self.buf[3]
            if length < 2 or length > LENGTH_MAX:
                self.bad_frames += 1
                del self.buf[:1]
                continue
            total = 4 + length
            if len(self.buf) < total:
                return out
            core = bytes(self.buf[2:total - 1])
            if checksum(core) != self.buf[total - 1]:
                self.bad_frames += 1
                del self.buf[:1]
                continue
            out.append(Frame(self.header, core[0], core[2:]))
            del self.buf[:total]
