# SPDX-License-Identifier: Apache-2.0
"""Byte transports to a servo bus, opened from one spec string, every one
through pyserial's serial_for_url (Debian: python3-serial):

    /dev/ttyUSB0[@BAUD]        a serial port or pseudo-terminal by its path
    socket://HOST:PORT         the emulated bus (sim/bus/servo-bus, host-sim --listen)
    rfc2217://HOST:PORT[@BAUD] the emulated bus as a serial port over RFC 2217
                               (sim/bus/servo-bus): the baud is the master's line
                               rate on the wire, set_baud() changes it
    loop://                    pyserial's loop-back: every byte written comes back
    spy:///dev/ttyUSB0[?file=F] the port with a hex trace of every byte (stderr or F)
    hwgrep://REGEXP[@BAUD]     the first serial adapter whose description matches
and kmx's short aliases:
    tcp:HOST:PORT              socket://HOST:PORT
    serial:/dev/ttyUSB0@115200 the device path (baud optional, default 115200)
    pty:/dev/pts/N             the path of a pseudo-terminal (host-sim --pty)
    rfc2217:HOST:PORT@BAUD     rfc2217://HOST:PORT@BAUD

Every failure is a KmxError subclass with a message that names the spec
and what to do, never a library traceback; a second client of servo-bus is
told "the bus is busy". A transport writes, reads what arrives within a
timeout, drops stale input and closes."""

import errno
import os
import re
import select
import socket
import stat
import termios
import warnings

from .deps import import_debian
from .errors import (ConnectionRefused, NoSuchDevice, NotASerialPort,
                     PortBusy, SpecError, TransportError)

DEFAULT_BAUD = 115200
BUSY_PREFIX = b"servo-bus: busy"  # sim/bus/servo-bus BUSY_LINE
SPEC_FORMS = ("tcp:HOST:PORT, serial:/dev/ttyUSB0@115200, pty:/dev/pts/N or rfc2217:HOST:PORT@115200; "
              "a device path /dev/ttyUSB0[@BAUD]; or a pyserial URL socket://, rfc2217://, loop://, "
              "spy://, hwgrep://")
URL_FORMS = "rfc2217://HOST:PORT[@BAUD] or socket://HOST:PORT"  # pyserial's URLs of the two network ports
URL_KINDS = {"rfc2217": "rfc2217", "socket": "tcp", "tcp": "tcp"}  # scheme -> the kind it opens
OTHER_URLS = ("loop", "spy", "hwgrep", "alt", "cp2110")  # pyserial's other handlers, opened as they are
BAUD_MIN, BAUD_MAX = 9600, 1000000  # what the servos can run at (0x10 x 100)


def _url_rest(spec, kind, rest):
    """The spec of a network URL (rfc2217://, socket://; tcp:// too) without
    its "//", so it parses as the colon form; SpecError for query options
    (kmx sets the port's options itself)."""
    rest = rest[2:]
    if "?" in rest or "/" in rest:
        raise SpecError("bus '%s': no path or ?options after HOST:PORT (kmx sets the port's options "
                        "itself); expected %s" % (spec, URL_FORMS))
    return URL_KINDS[kind], rest


def _with_baud(spec, text):
    """(text before a final @BAUD, the baud or DEFAULT_BAUD); SpecError for a bad baud."""
    head, sep, baud = text.rpartition("@")
    if not sep:
        return text, DEFAULT_BAUD
    if not baud.isdigit() or int(baud) <= 0:
        raise SpecError("bus '%s': the baud after @ must be a positive number" % spec)
    return head, int(baud)


def _is_device_path(spec):
    """A bare device: a path (/dev/ttyUSB0, ./port) or, on Windows, COMn."""
    return spec.startswith(("/", "./")) or (os.name == "nt" and re.match(r"(?i)^com\d+(@|$)", spec) is not None)


def parse_spec(spec):
    """Splits a spec string into (kind, params): ("tcp", {"host", "port"}),
    ("serial", {"path", "baud"}), ("pty", {"path"}), ("rfc2217", {"host",
    "port", "baud"}) or ("url", {"url", "baud"}) for pyserial's other URLs
    (loop://, spy://, hwgrep://); socket:// and rfc2217:// as their colon
    forms, a bare device path as serial. Raises SpecError."""
    if not isinstance(spec, str):
        raise SpecError("bus '%s': expected %s" % (spec, SPEC_FORMS))
    if _is_device_path(spec):
        path, baud = _with_baud(spec, spec)
        return "serial", {"path": path, "baud": baud}
    if ":" not in spec:
        raise SpecError("bus '%s': expected %s" % (spec, SPEC_FORMS))
    kind, rest = spec.split(":", 1)
    if rest.startswith("//"):
        if kind in OTHER_URLS:
            url, baud = _with_baud(spec, spec)
            return "url", {"url": url, "baud": baud}
        if kind not in URL_KINDS:
            raise SpecError("bus '%s': kmx opens no '%s://' URL; expected %s" % (spec, kind, SPEC_FORMS))
        kind, rest = _url_rest(spec, kind, rest)
    return _parse_colon_form(spec, kind, rest)


def _parse_colon_form(spec, kind, rest):
    """parse_spec for kmx's own forms KIND:REST (tcp, rfc2217, serial, pty)."""
    if kind == "rfc2217":
        addr, baud = _with_baud(spec, rest)
        host, hsep, port = addr.rpartition(":")
        if not hsep or not host or not port.isdigit() or not 1 <= int(port) <= 65535:
            raise SpecError("bus '%s': rfc2217 wants HOST:PORT[@BAUD], e.g. rfc2217:127.0.0.1:7000@115200" % spec)
        return "rfc2217", {"host": host, "port": int(port), "baud": baud}
    if kind == "tcp":
        host, sep, port = rest.rpartition(":")
        if not sep or not host:
            raise SpecError("bus '%s': tcp wants HOST:PORT, e.g. tcp:127.0.0.1:7000" % spec)
        if not port.isdigit() or not 1 <= int(port) <= 65535:
            raise SpecError("bus '%s': the TCP port must be a number in 1..65535" % spec)
        return "tcp", {"host": host, "port": int(port)}
    if kind == "serial":
        path, baud = _with_baud(spec, rest)
        if not path:
            raise SpecError("bus '%s': serial wants a device path, e.g. serial:/dev/ttyUSB0@115200" % spec)
        return "serial", {"path": path, "baud": baud}
    if kind == "pty":
        if not rest:
            raise SpecError("bus '%s': pty wants a path, e.g. pty:/dev/pts/3" % spec)
        return "pty", {"path": rest}
    raise SpecError("bus '%s': unknown transport '%s'; expected %s" % (spec, kind, SPEC_FORMS))


def import_serial():
    """pyserial, from this interpreter or Debian's python3-serial (kmx/deps.py)."""
    return import_debian("serial", "python3-serial", "kmx opens every bus through pyserial")


class Transport:
    """Base: write(data), read(timeout) -> bytes (b"" when nothing arrived),
    flush_input(), close(); a context manager."""

    spec = ""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self):
        return "<%s %s>" % (type(self).__name__, self.spec)


class PortTransport(Transport):
    """Any port pyserial's serial_for_url opens (8N1, §1): a device path,
    socket://, rfc2217://, loop://, spy://, hwgrep://. kind is parse_spec's."""

    def __init__(self, kind, url, baud, spec):
        self.spec, self.kind = spec, kind
        self.baud = None if kind == "tcp" else baud  # the emulated bus carries bytes, not a line rate
        serial = import_serial()
        self._errors = (serial.SerialException, OSError, termios.error, ValueError)
        if kind in ("serial", "pty"):
            _check_device(url, spec)
        try:
            with warnings.catch_warnings():  # pyserial 3.5's thread setDaemon()/setName() on Python >= 3.10
                warnings.simplefilter("ignore", DeprecationWarning)
                self.port = serial.serial_for_url(url, baudrate=baud, timeout=0, do_not_open=True)
                if kind in ("serial", "pty"):
                    self.port.exclusive = True
                # socket:// drains its input when it opens: servo-bus's busy line
                # would go with it, so that drain is left out
                self.port.reset_input_buffer = lambda: None
                try:
                    self.port.open()
                finally:
                    del self.port.reset_input_buffer
        except self._errors as e:
            raise _open_error(spec, kind, url, baud, e) from None
        if kind == "tcp":  # socket://: a frame goes out at once
            self.port._socket.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._fd = getattr(self.port, "fd", None)  # a native port: select() on it
        self._first = True  # servo-bus tells a second client it is busy in the first bytes

    @property
    def can_set_baud(self):
        """True if set_baud() changes a line rate: a serial port or RFC 2217."""
        return self.kind in ("serial", "pty", "rfc2217") or (self.kind == "url" and self._fd is not None)

    def _check_busy(self, data):
        if self._first and data:
            self._first = False
            if data.startswith(BUSY_PREFIX):
                raise PortBusy("%s: the bus is busy: another client holds it (servo-bus takes one "
                               "client at a time; close the other one)" % self.spec)

    def set_baud(self, baud):
        """The port's line rate from now on (the master's, on an RFC 2217 bus)."""
        try:
            self.port.baudrate = baud
        except self._errors as e:
            if "parameter change" in str(e) or "rejected value" in str(e):
                raise TransportError("%s: the bus refused %d baud (the servos run at %d..%d)"
                                     % (self.spec, baud, BAUD_MIN, BAUD_MAX)) from None
            raise TransportError("%s: cannot set %d baud: %s" % (self.spec, baud, e)) from None
        self.baud = baud

    def _gone(self, what, e):
        """The TransportError for an I/O failure: the peer closed, or the device went."""
        if "socket disconnected" in str(e):
            return TransportError("%s: the bus closed the connection" % self.spec)
        return TransportError("%s: %s failed (%s gone?): %s"
                              % (self.spec, what, "device" if self._fd is not None else "bus", e))

    def write(self, data):
        try:
            self.port.write(bytes(data))
            if self._fd is not None:
                self.port.flush()
        except self._errors as e:
            raise self._gone("write", e) from None

    def read(self, timeout):
        try:
            data = self._read_fd(timeout) if self._fd is not None else self._read_timed(timeout)
        except InterruptedError:
            return b""
        except self._errors as e:
            raise self._gone("read", e) from None
        self._check_busy(data)
        return data

    def _read_fd(self, timeout):
        """A native port: wait on its descriptor, then take what is there."""
        ready, _, _ = select.select([self._fd], [], [], max(0.0, timeout))
        if not ready:
            return b""
        return self.port.read(max(1, self.port.in_waiting))

    def _read_timed(self, timeout):
        """Any other port: one byte within timeout, then what is there."""
        self.port.timeout = max(0.0, timeout)
        first = self.port.read(1)
        if not first:
            thread = getattr(self.port, "_thread", False)  # RFC 2217's reader: gone with the connection
            if not self.port.is_open or thread is None or (thread and not thread.is_alive()):
                raise TransportError("%s: the bus closed the connection" % self.spec)
            return b""
        self.port.timeout = 0
        return first + self.port.read(4096)

    def flush_input(self):
        try:
            if self._fd is not None:
                self.port.reset_input_buffer()
                return
            self.port.timeout = 0
            while True:
                data = self.port.read(4096)
                if not data:
                    return
                self._check_busy(data)
        except self._errors as e:
            if "socket disconnected" in str(e):
                return  # the next read says so
            raise TransportError("%s: the bus is gone: %s" % (self.spec, e)) from None

    def close(self):
        """Closes the port. A socket:// port's own close() sleeps 0.3 s and
        leaves the socket open when the peer closed first (pyserial 3.5):
        its socket is closed here instead."""
        if self.port is None:
            return
        sock = getattr(self.port, "_socket", None) if self.kind == "tcp" else None
        if sock is not None:
            self.port._socket = None
            self.port.is_open = False
            sock.close()
        else:
            try:
                self.port.close()
            except self._errors:
                pass
        self.port = None


def _check_device(path, spec):
    """A device path must exist and be a character device (before pyserial
    tries it: a regular file would open)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise NoSuchDevice("%s: no such device %s" % (spec, path)) from None
    except OSError as e:
        raise TransportError("%s: cannot open %s: %s" % (spec, path, e.strerror)) from None
    if not stat.S_ISCHR(st.st_mode):
        raise NotASerialPort("%s: %s is not a serial port (not a character device)" % (spec, path))


def _open_error(spec, kind, url, baud, e):
    """The KmxError for a port pyserial could not open, by what went wrong."""
    text, code = str(e), getattr(e, "errno", None)
    if "Connection refused" in text or code == errno.ECONNREFUSED:
        return ConnectionRefused("%s: connection refused (is the bus running? start it with "
                                 "sim/bus/servo-bus or host-sim --listen)" % spec)
    if "parameter change" in text or "rejected value" in text:
        return TransportError("%s: the bus refused %d baud (the servos run at %d..%d)"
                              % (spec, baud, BAUD_MIN, BAUD_MAX))
    if kind == "rfc2217" and ("RFC2217" in text or "BINARY" in text):
        return TransportError("%s: the other end does not speak RFC 2217 (host-sim --listen "
                              "does not: use tcp:HOST:PORT)" % spec)
    if "no ports found matching" in text:
        return NoSuchDevice("%s: no serial adapter matches '%s' (python3 -m serial.tools.list_ports -v "
                            "lists them)" % (spec, url[len("hwgrep://"):]))
    if code == errno.ENOENT:
        return NoSuchDevice("%s: no such device %s" % (spec, url))
    if code in (errno.EACCES, errno.EPERM):
        return TransportError("%s: permission denied on %s (add yourself to group dialout)" % (spec, url))
    if code in (errno.EBUSY, errno.EAGAIN, errno.EWOULDBLOCK) or "exclusively lock" in text:
        return PortBusy("%s: %s is busy: another program holds it" % (spec, url))
    if "Inappropriate ioctl" in text or code == errno.ENOTTY:
        return NotASerialPort("%s: %s is not a serial port" % (spec, url))
    if "getaddrinfo" in text or "Name or service not known" in text:
        return TransportError("%s: cannot resolve the host (%s)" % (spec, text))
    return TransportError("%s: cannot open: %s" % (spec, text))


def open_transport(spec):
    """Opens the transport a spec string names (see the module doc), through
    pyserial's serial_for_url."""
    kind, p = parse_spec(spec)
    if kind == "tcp":
        return PortTransport(kind, "socket://%s:%d" % (p["host"], p["port"]), DEFAULT_BAUD, spec)
    if kind == "rfc2217":
        return PortTransport(kind, "rfc2217://%s:%d?ign_set_control&timeout=2" % (p["host"], p["port"]),
                             p["baud"], spec)
    if kind == "url":
        return PortTransport(kind, p["url"], p["baud"], spec)
    return PortTransport(kind, p["path"], p.get("baud", DEFAULT_BAUD), spec)
