# SPDX-License-Identifier: Apache-2.0
"""KINGMAX serial servo frames (docs/protocol.md §2, §3): checksum, command and
response encoders, the command and special-ID constants, and a stream parser
that resyncs on noise and counts checksum errors. Standard library only.

Frame layout: header(2) id length body checksum, where body is
  command frame  (F9 FF): command [address] parameters
  response frame (F9 F5): command address value-bytes, or one status byte
length = len(body) + 1 (the checksum), checksum = ~(id + length + sum(body)) & 0xFF.
"""

CMD_HEADER = b"\xF9\xFF"
RSP_HEADER = b"\xF9\xF5"

# §1 IDs
ID_MAX = 250
ID_SUPER = 0xFD      # query every servo; each answers in its own slot
ID_BROADCAST = 0xFE  # every servo executes, none answers

# §3 commands
PING = 0x01
READ = 0x02
WRITE = 0x03
SYNC_WRITE = 0x04
MULTI_READ = 0x82    # our extension (docs/): broadcast, listed servos answer in list order
MULTI_WRITE = 0x83
SYNC_EXECUTE = 0x84
UPDATE = 0x78        # firmware update (docs/update.md §4); sub 0x04 = STATUS
UPDATE_STATUS = 0x04
UPDATE_STATES = {0: "application", 1: "idle", 2: "receiving", 3: "verified", 4: "committed", 5: "failed"}
EXTENSION = 0x7F     # our extension reads (docs/protocol-decisions.md "Extension command 0x7F")
NO_ADDRESS = (PING, SYNC_EXECUTE)  # commands without an address byte (§2)
MULTI_WRITE_ADDRESSES = (0x64, 0x65, 0x66, 0x68, 0x6E, 0x6F)  # §3: 0x83 only these

# §5 registers the bus layer itself needs
REG_STATUS = 0x01
REG_RESTART = 0x02
REG_USERDATA_RESET = 0x03  # value 2 resets everything, the ID to 0 at once (docs/protocol-decisions.md)
REG_ID = 0x0F
REG_BAUD = 0x10
RESTART_MAGIC = b"\xE1\xE2\xE3\xE4"

LENGTH_MAX = 252  # a whole frame is at most 256 bytes

# §4 status byte, bit 7 first
STATUS_BITS = (
    (0x80, "running"),
    (0x40, "command failed"),
    (0x20, "command exception"),
    (0x10, "hardware fault"),
    (0x08, "stall protection"),
    (0x04, "temperature protection"),
    (0x02, "current protection"),
    (0x01, "voltage protection"),
)


def status_words(status):
    """The set bits of a §4 status byte in words, or ["ok"]."""
    words = [name for bit, name in STATUS_BITS if status & bit]
    return words or ["ok"]


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


def ext_read(dev_id, addr):
    """Extension read 0x7F: laid out like a read (docs/protocol-decisions.md)."""
    return encode_command(dev_id, EXTENSION, addr)


def restart(dev_id):
    """Write 0x02 with exactly E1 E2 E3 E4 (§3): restarts at once, no answer."""
    return write(dev_id, REG_RESTART, RESTART_MAGIC)


def sync_write(dev_id, addr, value):
    """0x04 to one servo: buffered until sync execute (§3)."""
    return encode_command(dev_id, SYNC_WRITE, addr, value)


def sync_execute(dev_id=ID_BROADCAST):
    """0x84, normally broadcast: every servo runs its buffered 0x04."""
    return encode_command(dev_id, SYNC_EXECUTE)


def multi_write(addr, entries):
    """0x83 to broadcast (§3): entries = [(id, data bytes)], all data the same
    length k; parameters are k, then id + data per servo."""
    entries = [(dev_id, bytes(data)) for dev_id, data in entries]
    if not entries:
        raise ValueError("multi-ID write needs at least one servo")
    k = len(entries[0][1])
    if k == 0 or any(len(data) != k for _, data in entries):
        raise ValueError("multi-ID write: every servo's data must have the same, non-zero length")
    if any(not 0 <= dev_id <= ID_MAX for dev_id, _ in entries):
        raise ValueError("multi-ID write: IDs must be in 0..%d" % ID_MAX)
    params = bytes([k]) + b"".join(bytes([dev_id]) + data for dev_id, data in entries)
    return encode_command(ID_BROADCAST, MULTI_WRITE, addr, params)


def multi_read(addr, ids):
    """0x82 to broadcast: F9 FF FE len 82 addr id1 .. idn chk; servo idk
    answers its normal read answer in slot k (position in the list)."""
    ids = list(ids)
    if not ids:
        raise ValueError("multi-ID read needs at least one servo")
    if any(not 0 <= i <= ID_MAX for i in ids) or len(set(ids)) != len(ids):
        raise ValueError("multi-ID read: IDs must be distinct, in 0..%d" % ID_MAX)
    return encode_command(ID_BROADCAST, MULTI_READ, addr, bytes(ids))


def encode_response(dev_id, cmd, addr, value=b""):
    """Response frame F9 F5 (e.g. the answer to a read)."""
    return _frame(RSP_HEADER, dev_id, bytes([cmd, addr]) + bytes(value))


def encode_status(dev_id, status):
    """Short response frame: F9 F5 id 02 status checksum."""
    return _frame(RSP_HEADER, dev_id, bytes([status]))


class Frame:
    """One checked frame. body is everything between length and checksum;
    time is when it arrived (time.monotonic(), set by the bus), or None."""

    def __init__(self, header, dev_id, body, time=None):
        self.header = bytes(header)
        self.id = dev_id
        self.body = bytes(body)
        self.time = time

    @property
    def is_response(self):
        return self.header == RSP_HEADER

    @property
    def is_command(self):
        return self.header == CMD_HEADER

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

    def __hash__(self):
        return hash((self.header, self.id, self.body))

    def __repr__(self):
        return "Frame(%s id=%d body=%s)" % (self.header.hex(), self.id, self.body.hex())


class Parser:
    """Byte-stream parser. feed() takes any chunk of bytes and returns the
    complete, checksum-valid frames in it, in order; a partial frame waits
    for the next chunk. headers: the frame kinds to recognise (responses
    only by default; a bus master on a half-duplex wire also parses its own
    command frames, to tell their echo from noise). On a bad checksum or
    length it skips one byte and hunts for the next header; counters:
      checksum_errors  frames whose checksum did not match
      length_errors    impossible length bytes (< 2 or > 252)
      noise_bytes      bytes skipped outside any frame
    bad_frames = checksum_errors + length_errors (the kmbus.py name)."""

    def __init__(self, header=RSP_HEADER, headers=None):
        self.headers = tuple(bytes(h) for h in (headers or (header,)))
        self.buf = bytearray()
        self.checksum_errors = 0
        self.length_errors = 0
        self.noise_bytes = 0

    @property
    def bad_frames(self):
        return self.checksum_errors + self.length_errors

    @property
    def header(self):
        return self.headers[0]

    def _find_header(self):
        found = [i for i in (self.buf.find(h) for h in self.headers) if i >= 0]
        return min(found) if found else -1

    def _drop(self, n):
        del self.buf[:n]

    def feed(self, data):
        self.buf += data
        out = []
        while True:
            start = self._find_header()
            if start < 0:
                # keep a trailing first header byte: the second may follow
                keep = 1 if any(self.buf[-1:] == h[:1] for h in self.headers) else 0
                self.noise_bytes += len(self.buf) - keep
                self._drop(len(self.buf) - keep)
                return out
            self.noise_bytes += start
            self._drop(start)
            if len(self.buf) < 4:
                return out
            length = self.buf[3]
            if length < 2 or length > LENGTH_MAX:
                self.length_errors += 1
                self.noise_bytes += 1
                self._drop(1)
                continue
            total = 4 + length
            if len(self.buf) < total:
                return out
            core = bytes(self.buf[2:total - 1])
            if checksum(core) != self.buf[total - 1]:
                self.checksum_errors += 1
                self.noise_bytes += 1
                self._drop(1)
                continue
            out.append(Frame(self.buf[:2], core[0], core[2:]))
            self._drop(total)
