# SPDX-License-Identifier: Apache-2.0
"""Byte transports to a servo bus, opened from one spec string:

    tcp:HOST:PORT              the emulated bus (tools/servo-bus, host-sim --listen)
    serial:/dev/ttyUSB0@115200 a real serial port (baud optional, default 115200)
    pty:/dev/pts/N             a pseudo-terminal (host-sim --pty)
    rfc2217:HOST:PORT@BAUD     the emulated bus as a serial port over RFC 2217
                               (tools/servo-bus): the baud is the master's
                               line rate on the wire, set_baud() changes it
    rfc2217://HOST:PORT[@BAUD] the same, written as pyserial's URL
    socket://HOST:PORT         pyserial's URL of a raw TCP socket: tcp:HOST:PORT

Serial ports and ptys go through pyserial (Debian: python3-serial); no
termios code here. Every failure is a KmxError subclass with a message that
names the spec and what to do, never a library traceback. A transport
writes, reads what arrives within a timeout, drops stale input and closes."""

import errno
import os
import select
import socket
import stat
import termios
import warnings

from .deps import import_debian
from .errors import (ConnectionRefused, NoSuchDevice, NotASerialPort,
                     PortBusy, SpecError, TransportError)

DEFAULT_BAUD = 115200
BUSY_PREFIX = b"servo-bus: busy"  # tools/servo-bus BUSY_LINE
SPEC_FORMS = "tcp:HOST:PORT, serial:/dev/ttyUSB0@115200, pty:/dev/pts/N or rfc2217:HOST:PORT@115200"
URL_FORMS = "rfc2217://HOST:PORT[@BAUD] or socket://HOST:PORT"  # pyserial's URLs of the two network ports
URL_KINDS = {"rfc2217": "rfc2217", "socket": "tcp", "tcp": "tcp"}  # scheme -> the kind it opens
BAUD_MIN, BAUD_MAX = 9600, 1000000  # what the servos can run at (0x10 x 100)


def _url_rest(spec, kind, rest):
    """The spec of a pyserial URL (rfc2217://, socket://; tcp:// too) without
    its "//", so it parses as the colon form; SpecError for the URL forms
    kmx does not open (query options, other schemes)."""
    if kind not in URL_KINDS:
        raise SpecError("bus '%s': kmx opens no '%s://' URL; expected %s, or %s"
                        % (spec, kind, SPEC_FORMS, URL_FORMS))
    rest = rest[2:]
    if "?" in rest or "/" in rest:
        raise SpecError("bus '%s': no path or ?options after HOST:PORT (kmx sets the port's options "
                        "itself); expected %s" % (spec, URL_FORMS))
    return URL_KINDS[kind], rest


def parse_spec(spec):
    """Splits a spec string into (kind, params): ("tcp", {"host", "port"}),
    ("serial", {"path", "baud"}), ("pty", {"path"}) or ("rfc2217", {"host",
    "port", "baud"}); pyserial's URLs rfc2217:// and socket:// as their
    colon forms. Raises SpecError."""
    if not isinstance(spec, str) or ":" not in spec:
        raise SpecError("bus '%s': expected %s" % (spec, SPEC_FORMS))
    kind, rest = spec.split(":", 1)
    if rest.startswith("//"):
        kind, rest = _url_rest(spec, kind, rest)
    if kind == "rfc2217":
        addr, sep, baud = rest.partition("@")
        host, hsep, port = addr.rpartition(":")
        if not hsep or not host or not port.isdigit() or not 1 <= int(port) <= 65535:
            raise SpecError("bus '%s': rfc2217 wants HOST:PORT[@BAUD], e.g. rfc2217:127.0.0.1:7000@115200" % spec)
        if sep and (not baud.isdigit() or int(baud) <= 0):
            raise SpecError("bus '%s': the baud after @ must be a positive number" % spec)
        return "rfc2217", {"host": host, "port": int(port), "baud": int(baud) if sep else DEFAULT_BAUD}
    if kind == "tcp":
        host, sep, port = rest.rpartition(":")
        if not sep or not host:
            raise SpecError("bus '%s': tcp wants HOST:PORT, e.g. tcp:127.0.0.1:7000" % spec)
        if not port.isdigit() or not 1 <= int(port) <= 65535:
            raise SpecError("bus '%s': the TCP port must be a number in 1..65535" % spec)
        return "tcp", {"host": host, "port": int(port)}
    if kind == "serial":
        path, sep, baud = rest.partition("@")
        if not path:
            raise SpecError("bus '%s': serial wants a device path, e.g. serial:/dev/ttyUSB0@115200" % spec)
        if sep and (not baud.isdigit() or int(baud) <= 0):
            raise SpecError("bus '%s': the baud after @ must be a positive number" % spec)
        return "serial", {"path": path, "baud": int(baud) if sep else DEFAULT_BAUD}
    if kind == "pty":
        if not rest:
            raise SpecError("bus '%s': pty wants a path, e.g. pty:/dev/pts/3" % spec)
        return "pty", {"path": rest}
    raise SpecError("bus '%s': unknown transport '%s'; expected %s, or %s" % (spec, kind, SPEC_FORMS, URL_FORMS))


def import_serial():
    """pyserial, from this interpreter or Debian's python3-serial (kmx/deps.py)."""
    return import_debian("serial", "python3-serial", "serial ports and ptys need pyserial")


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


class TcpTransport(Transport):
    baud = None  # the emulated bus carries bytes, not a line rate

    def __init__(self, host, port, spec=None, connect_timeout=3.0):
        self.spec = spec or "tcp:%s:%d" % (host, port)
        try:
            self.sock = socket.create_connection((host, port), timeout=connect_timeout)
        except ConnectionRefusedError:
            raise ConnectionRefused("%s: connection refused (is the bus running? start it with "
                                    "tools/servo-bus or host-sim --listen)" % self.spec) from None
        except socket.gaierror as e:
            raise TransportError("%s: cannot resolve host '%s' (%s)" % (self.spec, host, e.strerror)) from None
        except (socket.timeout, TimeoutError):
            raise TransportError("%s: no connection within %.1f s" % (self.spec, connect_timeout)) from None
        except OSError as e:
            raise TransportError("%s: cannot connect: %s" % (self.spec, e.strerror or e)) from None
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.sock.setblocking(False)
        self._first = True  # servo-bus tells a second client it is busy in the first bytes

    def _check_busy(self, data):
        if self._first and data:
            self._first = False
            if data.startswith(BUSY_PREFIX):
                raise PortBusy("%s: the bus is busy: another client holds it (servo-bus takes one "
                               "client at a time; close the other one)" % self.spec)

    def write(self, data):
        try:
            self.sock.setblocking(True)
            self.sock.sendall(bytes(data))
        except OSError as e:
            raise TransportError("%s: write failed: %s" % (self.spec, e.strerror or e)) from None
        finally:
            self.sock.setblocking(False)

    def read(self, timeout):
        try:
            ready, _, _ = select.select([self.sock], [], [], max(0.0, timeout))
            if not ready:
                return b""
            data = self.sock.recv(4096)
        except (BlockingIOError, InterruptedError):
            return b""
        except OSError as e:
            raise TransportError("%s: read failed: %s" % (self.spec, e.strerror or e)) from None
        self._check_busy(data)
        if not data:
            raise TransportError("%s: the bus closed the connection" % self.spec)
        return data

    def flush_input(self):
        while True:
            try:
                data = self.sock.recv(4096)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return
            self._check_busy(data)
            if not data:
                return

    def close(self):
        if self.sock is not None:
            self.sock.close()
            self.sock = None


class SerialTransport(Transport):
    """A serial port or pseudo-terminal through pyserial (8N1, §1)."""

    def __init__(self, path, baud=DEFAULT_BAUD, spec=None):
        self.spec = spec or "serial:%s@%d" % (path, baud)
        self.baud = baud
        serial = import_serial()
        try:
            st = os.stat(path)
        except FileNotFoundError:
            raise NoSuchDevice("%s: no such device %s" % (self.spec, path)) from None
        except OSError as e:
            raise TransportError("%s: cannot open %s: %s" % (self.spec, path, e.strerror)) from None
        if not stat.S_ISCHR(st.st_mode):
            raise NotASerialPort("%s: %s is not a serial port (not a character device)" % (self.spec, path))
        try:
            self.port = serial.Serial(path, baud, bytesize=8, parity="N", stopbits=1,
                                      timeout=0, exclusive=True)
        except serial.SerialException as e:
            code = e.errno
            text = str(e)
            if code == errno.ENOENT:
                raise NoSuchDevice("%s: no such device %s" % (self.spec, path)) from None
            if code in (errno.EACCES, errno.EPERM):
                raise TransportError("%s: permission denied on %s (add yourself to group dialout)"
                                     % (self.spec, path)) from None
            if code in (errno.EBUSY, errno.EAGAIN, errno.EWOULDBLOCK) or "exclusively lock" in text:
                raise PortBusy("%s: %s is busy: another program holds it" % (self.spec, path)) from None
            if "Inappropriate ioctl" in text or code == errno.ENOTTY:
                raise NotASerialPort("%s: %s is not a serial port" % (self.spec, path)) from None
            raise TransportError("%s: cannot open %s: %s" % (self.spec, path, text)) from None
        except (OSError, ValueError) as e:
            raise TransportError("%s: cannot open %s: %s" % (self.spec, path, e)) from None
        # what pyserial lets through when the device goes away (a pty whose
        # other side closed answers tcflush with termios.error EIO)
        self._errors = (serial.SerialException, OSError, termios.error, ValueError)

    def set_baud(self, baud):
        """The port's line rate from now on."""
        try:
            self.port.baudrate = baud
        except self._errors as e:
            raise TransportError("%s: cannot set %d baud: %s" % (self.spec, baud, e)) from None
        self.baud = baud

    def write(self, data):
        try:
            self.port.write(bytes(data))
            self.port.flush()
        except self._errors as e:
            raise TransportError("%s: write failed (device gone?): %s" % (self.spec, e)) from None

    def read(self, timeout):
        try:
            ready, _, _ = select.select([self.port.fileno()], [], [], max(0.0, timeout))
            if not ready:
                return b""
            return self.port.read(max(1, self.port.in_waiting))
        except InterruptedError:
            return b""
        except self._errors as e:
            raise TransportError("%s: read failed (device gone?): %s" % (self.spec, e)) from None

    def flush_input(self):
        try:
            self.port.reset_input_buffer()
        except self._errors as e:
            raise TransportError("%s: the device is gone: %s" % (self.spec, e)) from None

    def close(self):
        if self.port is not None:
            self.port.close()
            self.port = None


class Rfc2217Transport(Transport):
    """The emulated bus as a serial port (RFC 2217, pyserial's client): the
    master's baud on the wire is this port's (tools/servo-bus "Baud")."""

    def __init__(self, host, port, baud=DEFAULT_BAUD, spec=None):
        self.spec = spec or "rfc2217:%s:%d@%d" % (host, port, baud)
        self.baud = baud
        serial = import_serial()
        self._serial_exc = serial.SerialException
        try:
            with warnings.catch_warnings():  # pyserial 3.5's thread setDaemon()/setName() on Python >= 3.10
                warnings.simplefilter("ignore", DeprecationWarning)
                self.port = serial.serial_for_url("rfc2217://%s:%d?ign_set_control&timeout=2" % (host, port),
                                                  baudrate=baud, timeout=0)
        except (serial.SerialException, ValueError) as e:
            text = str(e)
            if "Connection refused" in text:
                raise ConnectionRefused("%s: connection refused (is the bus running? start it with "
                                        "tools/servo-bus)" % self.spec) from None
            if "parameter change" in text or "rejected value" in text:
                raise TransportError("%s: the bus refused %d baud (the servos run at %d..%d)"
                                     % (self.spec, baud, BAUD_MIN, BAUD_MAX)) from None
            if "RFC2217" in text or "BINARY" in text:
                raise TransportError("%s: the other end does not speak RFC 2217 (host-sim --listen "
                                     "does not: use tcp:HOST:PORT)" % self.spec) from None
            raise TransportError("%s: cannot open: %s" % (self.spec, text)) from None
        except OSError as e:
            raise TransportError("%s: cannot open: %s" % (self.spec, e)) from None
        self._errors = (serial.SerialException, OSError, ValueError)

    def set_baud(self, baud):
        """The master's line rate from now on (a serial adapter's baud)."""
        try:
            self.port.baudrate = baud
        except self._errors as e:
            if "parameter change" in str(e) or "rejected value" in str(e):
                raise TransportError("%s: the bus refused %d baud (the servos run at %d..%d)"
                                     % (self.spec, baud, BAUD_MIN, BAUD_MAX)) from None
            raise TransportError("%s: cannot set %d baud: %s" % (self.spec, baud, e)) from None
        self.baud = baud

    def write(self, data):
        try:
            self.port.write(bytes(data))
        except self._errors as e:
            raise TransportError("%s: write failed (bus gone?): %s" % (self.spec, e)) from None

    def read(self, timeout):
        try:
            self.port.timeout = max(0.0, timeout)
            first = self.port.read(1)
            if not first:
                if not self.port.is_open or self.port._thread is None or not self.port._thread.is_alive():
                    raise TransportError("%s: the bus closed the connection" % self.spec)
                return b""
            self.port.timeout = 0
            return first + self.port.read(max(0, self.port.in_waiting))
        except self._errors as e:
            raise TransportError("%s: read failed (bus gone?): %s" % (self.spec, e)) from None

    def flush_input(self):
        try:
            self.port.timeout = 0
            while self.port.read(4096):
                pass
        except self._errors as e:
            raise TransportError("%s: the bus is gone: %s" % (self.spec, e)) from None

    def close(self):
        if self.port is not None:
            try:
                self.port.close()
            except self._errors:
                pass
            self.port = None


def open_transport(spec):
    """Opens the transport a spec string names (see the module doc)."""
    kind, p = parse_spec(spec)
    if kind == "tcp":
        return TcpTransport(p["host"], p["port"], spec)
    if kind == "serial":
        return SerialTransport(p["path"], p["baud"], spec)
    if kind == "rfc2217":
        return Rfc2217Transport(p["host"], p["port"], p["baud"], spec)
    return SerialTransport(p["path"], DEFAULT_BAUD, spec)
