# SPDX-License-Identifier: Apache-2.0
"""The bus master (docs/protocol.md §1, §3) over a transport: one question, the
answers it expects within a timeout, each stamped with its arrival time.
Echoes of its own command frames (a half-duplex wire hears the master's
bytes back) are parsed and dropped, never taken for noise or answers.
Reads and pings retry; writes are sent once (a retried write may act twice).
A write that changes an ID (0x0F, or 0x03 = 2, which sets it to 0) is
refused with IdTaken when another servo answers on the new ID, or when two
servos already share the old one (it would move both): two servos on one
ID cannot be told apart by any frame afterwards (docs/protocol.md §5.1 0x01).
transact() and send_bytes() send raw frames and check nothing.

    bus = Bus(open_transport("tcp:127.0.0.1:7000"))
    bus.ping(1) -> status byte        bus.read(1, 0x46) -> value bytes
    bus.scan() -> [(id, status)]      bus.multi_read(0x46, [1, 2, 3]) -> {id: bytes}
    bus.shared_ids([1, 2]) -> {id: how two servos on it showed}
"""

import time

from . import frame as fr
from .errors import BadAnswer, IdTaken, InUpdateMode, NoAnswer
from .transport import open_transport

DEFAULT_TIMEOUT = 0.1      # one answer at any standard baud, with host slack
DEFAULT_RETRIES = 2        # extra attempts of a read or ping
BOOT_TIMEOUT = 3.0         # a restarted servo answers pings again within this
DEFAULT_DELAY_US = 200     # 0x12 response delay, a fresh servo's (§5.1)
PING_ANSWER = 6            # bytes of a short response (§2)
READ_ANSWER_MAX = 7 + 16   # the longest read answer (0x0A, 16 B of text)
STATUS_READ_ANSWER = 7 + 2  # a read answer of 0x01: [status][random]


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
                    last.status = getattr(problem, "status", None)
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

    def update_state(self, dev_id, timeout=None):
        """0x78 STATUS (docs/update.md §4): the update state of dev_id, 0 for
        an application, 1..5 for its bootloader (idle, receiving, verified,
        committed, failed); None when no STATUS answer comes (firmware
        without 0x78, or nobody on dev_id)."""
        data = fr.encode_command(dev_id, fr.UPDATE, fr.UPDATE_STATUS, b"\x00\x00")
        for _ in range(1 + self.retries):
            for f in self.transact(data, 1, self.timeout if timeout is None else timeout):
                if f.id == dev_id and not f.is_status and f.cmd == fr.UPDATE and f.addr == fr.UPDATE_STATUS \
                        and len(f.params) >= 1:
                    return f.params[0]
        return None

    def check_update_mode(self, dev_id):
        """Raises InUpdateMode when dev_id answers from its bootloader: the
        reason a servo refuses every read and write but 0x01 and 0x0C."""
        state = self.update_state(dev_id)
        if state:
            raise InUpdateMode(
                "ID %d is in update mode (its bootloader runs, state %s; no application): run `kmx --bus %s "
                "update --ids %d IMAGE.kmfw` to finish the update (docs/update.md)"
                % (dev_id, fr.UPDATE_STATES.get(state, state), self.transport.spec, dev_id))

    def read_frame(self, dev_id, addr, timeout=None):
        """Read (0x02): the whole answer frame (for its arrival time). A
        servo that answers "not supported" (§4 bit 5) from its bootloader
        raises InUpdateMode."""
        try:
            return self._read_frame(dev_id, addr, timeout)
        except BadAnswer as e:
            if getattr(e, "status", 0) & 0x20:
                self.check_update_mode(dev_id)
            raise

    def _read_frame(self, dev_id, addr, timeout=None):
        """Read (0x02) as it is, without the update-mode check."""
        def accept(f):
            if f.is_status:
                return _StatusInstead("a status 0x%02X instead of the value (%s)" % (
                    f.status, ", ".join(fr.status_words(f.status))), f.status)
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
        self.check_id_change(dev_id, addr, value)
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
        """Sync write (0x04): buffered by the servo until execute(). An ID
        change is checked as write() checks it."""
        self.check_id_change(dev_id, addr, value)
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

    # -- one servo per ID (§1, §5.1 0x01) ----------------------------------
    def check_id_change(self, dev_id, addr, value):
        """Raises IdTaken if writing value at addr to dev_id would leave two
        servos on one ID: 0x0F = N (or 0x03 = 2, the ID to 0) while another
        servo answers on N, or while two servos share dev_id; to broadcast,
        while more than one servo answers a scan. Other writes pass."""
        value = bytes(value)
        if addr == fr.REG_ID and len(value) == 1:
            new_id = value[0]
        elif addr == fr.REG_USERDATA_RESET and value == b"\x02":
            new_id = 0
        else:
            return
        if new_id > fr.ID_MAX or dev_id == new_id or (dev_id > fr.ID_MAX and dev_id != fr.ID_BROADCAST):
            return  # refused by the servo (bit 6), no change, or nobody acts on it (super ID, 251, 252, 255)
        if dev_id == fr.ID_BROADCAST:
            self._check_broadcast_id(new_id)
            return
        if self.answers_on(new_id):
            raise IdTaken("ID %d is taken: another servo answers there" % new_id)
        shared = self.shared_id(dev_id)
        if shared:
            raise IdTaken("two servos answer on ID %d, which gave %s: the write would move both to ID %d; "
                          "disconnect all but one of them first" % (dev_id, shared, new_id))

    def _check_broadcast_id(self, new_id):
        """A broadcast write of an ID reaches every servo: one at most may hear it."""
        found = self.scan()
        if len(found) > 1:
            raise IdTaken("a broadcast write would give all %d servos on the bus (IDs %s) ID %d; "
                          "write to one servo's own ID" % (len(found), ", ".join(str(i) for i, _ in found), new_id))

    def answers_on(self, dev_id):
        """True if a servo answers a ping on dev_id (with the bus's retries).
        A late answer from another ID (a second servo on an ID just asked)
        does not count."""
        for _ in range(1 + self.retries):
            if any(f.id == dev_id for f in self.transact(fr.ping(dev_id), 0, self.timeout)):
                return True
        return False

    def shared_id(self, dev_id, tries=3):
        """How two or more servos answering on dev_id showed (words: "2
        answers to one read of 0x01 (random bytes 0x23, 0x59)"), or None (one
        servo, or none). docs/protocol.md §5.1: 0x01 reads [status][random], the
        random byte new in every answer, so two servos' answers to one read
        differ: on the emulated bus both arrive, on a wire they collide and
        fail the checksum. Reads 0x01 and listens the whole timeout; a read
        that came back garbled with no clean answer is tried again, and
        garbled every time counts as two servos."""
        garbled = 0
        for _ in range(tries):
            bad_before = self.parser.bad_frames
            answers = self._status_reads(self.transact(fr.read(dev_id, fr.REG_STATUS), 0, self.timeout), dev_id)
            if len(answers) > 1:
                return _twice(answers)
            if self.parser.bad_frames == bad_before:
                return None  # one clean answer, or nobody at all
            garbled += 1
        return "garbled answers to %d reads of 0x01 (answers colliding)" % garbled

    @staticmethod
    def _status_reads(frames, dev_id):
        """The random bytes of the 0x01 read answers from dev_id among frames."""
        return [f.params[1] for f in frames if f.id == dev_id and not f.is_status and f.cmd == fr.READ
                and f.addr == fr.REG_STATUS and len(f.params) == 2]

    def shared_ids(self, found):
        """{id: how it showed} for every ID that more than one servo answers
        on, among found (a scan's [(id, status)]): an ID in the scan twice,
        or a super-ID read of 0x01 (§1: every servo answers in its slot)
        answered twice on one ID; an ID whose 0x01 answer is missing or
        came back garbled is asked on its own (shared_id)."""
        ids = [i for i, _ in found]
        out = {i: "%d answers to the super-ID ping" % ids.count(i) for i in set(ids) if ids.count(i) > 1}
        if not ids:
            return out
        window = slots_window_s(max(ids) + 1, STATUS_READ_ANSWER, self.baud) + self.timeout
        bad_before = self.parser.bad_frames
        frames = self.transact(fr.read(fr.ID_SUPER, fr.REG_STATUS), 0, window)
        garbled = self.parser.bad_frames > bad_before
        for i in sorted(set(ids)):
            answers = self._status_reads(frames, i)
            if len(answers) > 1:
                out[i] = _twice(answers)
            elif i not in out and (garbled or not answers):
                shared = self.shared_id(i)
                if shared:
                    out[i] = shared
        return out


class _StatusInstead(str):
    """An accept() complaint about a short response: its words and its status byte."""

    def __new__(cls, text, status):
        obj = super().__new__(cls, text)
        obj.status = status
        return obj


def _twice(randoms):
    """Words for the answers of servos sharing an ID, by their random bytes."""
    return "%d answers to one read of 0x01 (random bytes %s)" % (
        len(randoms), ", ".join("0x%02X" % r for r in randoms))
