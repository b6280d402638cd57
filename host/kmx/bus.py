"""The bus master (PROTOCOL.md §1, §3) over a transport: one question, the
answers it expects within a timeout, each stamped with its arrival time.
Echoes of its own command frames (a half-duplex wire hears the master's
bytes back) are parsed and dropped, never taken for noise or answers.
Reads and pings retry; writes are sent once (a retried write may act twice).

    bus = Bus(open_transport("tcp:127.0.0.1:7000"))
    bus.ping(1) -> status byte        bus.read(1, 0x46) -> value bytes
    bus.scan() -> [(id, status)]      bus.multi_read(0x46, [1, 2, 3]) -> {id: bytes}
"""

import time

from . import frame as fr
from .errors import BadAnswer, NoAnswer
from .transport import open_transport

DEFAULT_TIMEOUT = 0.1      # one answer at any standard baud, with host slack
DEFAULT_RETRIES = 2        # extra attempts of a read or ping
BOOT_TIMEOUT = 3.0         # a restarted servo answers pings again within this
DEFAULT_DELAY_US = 200     # 0x12 response delay, a fresh servo's (§5.1)
PING_ANSWER = 6            # bytes of a short response (§2)
READ_ANSWER_MAX = 7 + 16   # the longest read answer (0x0A, 16 B of text)


def slot_us(answer_bytes, baud):
    """One answer slot (docs/protocol-decisions.md "Super-ID answer slots"):
    the longest answer plus 2 guard bytes at 10 bits a byte, rounded up."""
    return -(-(answer_bytes + 2) * 10 * 1000000 // baud)


def slots_window_s(count, answer_bytes, baud, delay_us=DEFAULT_DELAY_US):
    """Seconds from the end of a super-ID or 0x82 question until the answer
    in slot count-1 has ended: 0x12 + (count - 1) x slot + the answer."""
    return (delay_us + (count - 1) * slot_us(answer_bytes, baud)
            + answer_bytes * 10 * 1000000 / baud) / 1e6


class Bus:
    def __init__(self, transport, timeout=DEFAULT_TIMEOUT, retries=DEFAULT_RETRIES, trace=None):
        if isinstance(transport, str):
            transport = open_transport(transport)
        self.transport = transport
        self.timeout = timeout
        self.retries = retries
        self.parser = fr.Parser(headers=(fr.RSP_HEADER, fr.CMD_HEADER))
        self.echoes = 0           # own command frames heard back
        self.foreign_commands = 0  # command frames we did not send (another master?)
        self.transactions = 0
        # trace(direction, item): ("tx", bytes) for every frame sent,
        # ("rx", Frame) for every answer taken; for session logs (--trace)
        self.trace = trace

    # -- context manager ---------------------------------------------------
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        self.transport.close()

    @property
    def checksum_errors(self):
        return self.parser.checksum_errors

    # -- raw ---------------------------------------------------------------
    def send_bytes(self, data):
        """Writes raw bytes (any frame, valid or not) as they are."""
        if self.trace:
            self.trace("tx", bytes(data))
        self.transport.write(bytes(data))

    def _answers_from(self, chunk, sent, now):
        out = []
        for f in self.parser.feed(chunk):
            if f.is_command:
                if f.to_bytes() in sent:
                    self.echoes += 1
                else:
                    self.foreign_commands += 1
                continue
            f.time = now
            if self.trace:
                self.trace("rx", f)
            out.append(f)
        return out

    def listen(self, timeout, answers=None, sent=()):
        """Collects answer frames until `answers` arrived or `timeout`
        seconds passed, whichever is first."""
        deadline = time.monotonic() + timeout
        out = []
        while answers is None or len(out) < answers:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            chunk = self.transport.read(left)
            if chunk:
                out += self._answers_from(chunk, sent, time.monotonic())
        return out

    def transact(self, data, answers=0, timeout=None):
        """Sends one frame (or several, as a list) and returns the answer
        frames that arrive: up to `answers` of them within `timeout`
        (default: the bus timeout). answers=0 returns at once unless a
        timeout is given, then it listens that long for strays."""
        frames = [bytes(d) for d in data] if isinstance(data, (list, tuple)) else [bytes(data)]
        self.transport.flush_input()
        self.parser.buf.clear()  # a partial frame from before is stale
        self.transactions += 1
        for f in frames:
            if self.trace:
                self.trace("tx", f)
            self.transport.write(f)
        self.sent_at = time.monotonic()
        if answers == 0 and timeout is None:
            return []
        return self.listen(self.timeout if timeout is None else timeout,
                           answers if answers else None, set(frames))

    def _ask(self, data, dev_id, accept, what, timeout=None):
        """One answer from dev_id that `accept` takes, with retries."""
        tries = 1 + self.retries
        wait = self.timeout if timeout is None else timeout
        last = None
        for _ in range(tries):
            frames = self.transact(data, 1, wait)
            deadline = self.sent_at + wait
            while frames:
                for f in frames:
                    if f.id != dev_id:
                        last = BadAnswer("%s: answer from ID %d, asked ID %d" % (what, f.id, dev_id))
                        continue
                    problem = accept(f)
                    if problem is None:
                        return f
                    last = BadAnswer("%s: %s" % (what, problem))
                # a stray (a late answer to an earlier frame): keep listening
                left = deadline - time.monotonic()
                frames = self.listen(left, 1, {bytes(data)}) if left > 0 else []
        if last is not None:
            raise last
        raise NoAnswer("%s: no answer from ID %d within %.0f ms (%d tries)%s" %
                       (what, dev_id, 1000 * (timeout or self.timeout), tries,
                        "; %d checksum errors heard" % self.checksum_errors if self.checksum_errors else ""))

    # -- commands (§3) -----------------------------------------------------
    def ping(self, dev_id, timeout=None):
        """Ping (0x01): the servo's status byte (§4)."""
        f = self._ask(fr.ping(dev_id), dev_id,
                      lambda f: None if f.is_status else "not a short response: %r" % f,
                      "ping ID %d" % dev_id, timeout)
        return f.status

    def read_frame(self, dev_id, addr, timeout=None):
        """Read (0x02): the whole answer frame (for its arrival time)."""
        def accept(f):
            if f.is_status:
                return "a status 0x%02X instead of the value (%s)" % (
                    f.status, ", ".join(fr.status_words(f.status)))
            if f.cmd != fr.READ or f.addr != addr:
                return "answer to command 0x%02X address 0x%02X, asked a read of 0x%02X" % (
                    f.cmd, f.addr if f.addr is not None else 0, addr)
            return None
        return self._ask(fr.read(dev_id, addr), dev_id, accept,
                         "read 0x%02X of ID %d" % (addr, dev_id), timeout)

    def ext_read(self, dev_id, addr, timeout=None):
        """Extension read (0x7F, our own: docs/protocol-decisions.md): the
        value bytes of extension address addr (boot source, reset cause,
        fault log)."""
        def accept(f):
            if f.is_status:
                return "a status 0x%02X instead of the value (%s)" % (
                    f.status, ", ".join(fr.status_words(f.status)))
            if f.cmd != fr.EXTENSION or f.addr != addr:
                return "answer to command 0x%02X, asked an extension read of 0x%02X" % (f.cmd, addr)
            return None
        return self._ask(fr.ext_read(dev_id, addr), dev_id, accept,
                         "extension read 0x%02X of ID %d" % (addr, dev_id), timeout).params

    def read(self, dev_id, addr, timeout=None):
        """Read (0x02): the value bytes of register addr."""
        return self.read_frame(dev_id, addr, timeout).params

    def write(self, dev_id, addr, value, answer=False, timeout=None):
        """Write (0x03), sent once. answer=True (response level 1, §5.1 0x11
        bit 3) waits for the short response and returns its status;
        otherwise returns None at once. A short response names no command:
        one that arrives late can be taken for the answer to the next
        question, so with response level 1 pass answer=True."""
        data = fr.write(dev_id, addr, value)
        if not answer:
            self.transact(data)
            return None
        got = self.transact(data, 1, timeout)
        if not got:
            raise NoAnswer("write 0x%02X of ID %d: no status answer within %.0f ms"
                           % (addr, dev_id, 1000 * (timeout or self.timeout)))
        if not got[0].is_status or got[0].id != dev_id:
            raise BadAnswer("write 0x%02X of ID %d: unexpected answer %r" % (addr, dev_id, got[0]))
        return got[0].status

    def restart(self, dev_id, wait=True, boot_timeout=BOOT_TIMEOUT):
        """Restart (write 0x02 = E1 E2 E3 E4): no answer. wait=True pings
        until the servo answers again (not for broadcast) and returns the
        seconds that took."""
        t0 = time.monotonic()
        self.transact(fr.restart(dev_id))
        if not wait or dev_id in (fr.ID_BROADCAST, fr.ID_SUPER):
            return None
        deadline = t0 + boot_timeout
        while time.monotonic() < deadline:
            if self.transact(fr.ping(dev_id), 1, min(0.05, self.timeout)):
                return time.monotonic() - t0
        raise NoAnswer("restart of ID %d: no answer within %.1f s after it" % (dev_id, boot_timeout))

    @property
    def baud(self):
        """The line rate answers travel at: the serial port's, else the
        emulated bus's nominal 115200 (a fresh servo's, §1)."""
        return getattr(self.transport, "baud", None) or 115200

    def scan_window(self):
        """How long ID 250's super-ID ping answer may take at this baud with
        a fresh servo's response delay, plus the bus timeout as host slack:
        0.27 s at 115200, 2.2 s at 9600."""
        return slots_window_s(fr.ID_MAX + 1, PING_ANSWER, self.baud) + self.timeout

    def scan(self, timeout=None, expect=None):
        """Super-ID ping (0xFD, §1): every servo answers in its slot, ID
        order. Returns [(id, status)] in arrival order; listens `timeout`
        seconds (default scan_window()), or until `expect` servos answered."""
        return [(f.id, f.status) for f in self.scan_frames(timeout, expect)]

    def scan_frames(self, timeout=None, expect=None):
        """The same, as the answer frames with their arrival times."""
        return [f for f in self.transact(fr.ping(fr.ID_SUPER), expect or fr.ID_MAX + 1,
                                         self.scan_window() if timeout is None else timeout)
                if f.is_status]

    def sync_write(self, dev_id, addr, value):
        """Sync write (0x04): buffered by the servo until execute()."""
        self.transact(fr.sync_write(dev_id, addr, value))

    def execute(self, dev_id=fr.ID_BROADCAST):
        """Sync write execute (0x84), broadcast by default."""
        self.transact(fr.sync_execute(dev_id))

    def multi_write(self, addr, entries):
        """Multi-ID write (0x83): entries {id: bytes} or [(id, bytes)]."""
        items = entries.items() if isinstance(entries, dict) else entries
        self.transact(fr.multi_write(addr, items))

    def multi_read(self, addr, ids, timeout=None):
        """Multi-ID read (0x82): one broadcast frame, each listed servo
        answers its read answer in the slot of its list position. Returns
        {id: value bytes}, None for a servo that did not answer."""
        ids = list(ids)
        got = self.multi_read_frames(addr, ids, timeout)
        out = {i: None for i in ids}
        for f in got:
            if f.id in out and not f.is_status and f.cmd == fr.READ and f.addr == addr:
                out[f.id] = f.params
        return out

    def multi_read_frames(self, addr, ids, timeout=None):
        """The same, as the answer frames in arrival order."""
        ids = list(ids)
        if timeout is None:  # the last slot's answer, cut for the longest read, plus host slack
            timeout = slots_window_s(len(ids), READ_ANSWER_MAX, self.baud) + self.timeout
        return self.transact(fr.multi_read(addr, ids), len(ids), timeout)
