# SPDX-License-Identifier: Apache-2.0
"""Every failure kmx reports, as one exception hierarchy under KmxError, so
a tool catches KmxError and prints its message: no library traceback
reaches a user. Messages say what happened and what to do."""


class KmxError(Exception):
    """Base of every kmx error; str() is a complete one-line message."""


class SpecError(KmxError):
    """A bus spec string (tcp:HOST:PORT, serial:DEV@BAUD, pty:PATH) is malformed."""


class MissingPackage(KmxError):
    """A Debian package the operation needs is not installed."""


class TransportError(KmxError):
    """The transport failed: cannot open, closed by the peer, I/O error."""


class ConnectionRefused(TransportError):
    """Nothing listens at a TCP address."""


class NoSuchDevice(TransportError):
    """A serial or pty path does not exist."""


class NotASerialPort(TransportError):
    """A path exists but is not a terminal device."""


class PortBusy(TransportError):
    """Another program holds the port."""


class NoAnswer(KmxError):
    """A servo did not answer within the timeout (after retries)."""


class BadAnswer(KmxError):
    """An answer arrived but does not fit the question (ID, command, address, length)."""


class RegisterError(KmxError):
    """Unknown register name or address, or an access it does not allow."""


class RangeError(KmxError):
    """A value does not fit the register (type, range, field count): refused before sending."""


class IdTaken(KmxError):
    """A write that changes a servo's ID (0x0F, or a 0x03 level-2 reset)
    would leave two servos on one ID: refused before anything is sent."""


class InUpdateMode(KmxError):
    """The servo answers from its bootloader (0x78 STATUS state 1..5,
    docs/update.md §4): no application runs, only an update finishes it."""
