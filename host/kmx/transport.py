"""Byte transports to a servo bus, opened from one spec string:

    tcp:HOST:PORT              the emulated bus (tools/servo-bus, host-sim --listen)
    serial:/dev/ttyUSB0@115200 a real serial port (baud optional, default 115200)
    pty:/dev/pts/N             a pseudo-terminal (host-sim --pty)

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

from .deps import import_debian
from .errors import (ConnectionRefused, NoSuchDevice, NotASerialPort,
                     PortBusy, SpecError, TransportError)

DEFAULT_BAUD = 115200
SPEC_FORMS = "tcp:HOST:PORT, serial:/dev/ttyUSB0@115200 or pty:/dev/pts/N"


def parse_spec(spec):
    """Splits a spec string into (kind, params): ("tcp", {"host", "port"}),
    ("serial", {"path", "baud"}) or ("pty", {"path"}). Raises SpecError."""
    if not isinstance(spec, str) or ":" not in spec:
        raise SpecError("bus '%s': expected %s" % (spec, SPEC_FORMS))
    kind, rest = spec.split(":", 1)
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
    raise SpecError("bus '%s': unknown transport '%s'; expected %s" % (spec, kind, SPEC_FORMS))


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
        if not data:
            raise TransportError("%s: the bus closed the connection" % self.spec)
        return data

    def flush_input(self):
        while True:
            try:
                if not self.sock.recv(4096):
                    return
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
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


def open_transport(spec):
    """Opens the transport a spec string names (see the module doc)."""
    kind, p = parse_spec(spec)
    if kind == "tcp":
        return TcpTransport(p["host"], p["port"], spec)
    if kind == "serial":
        return SerialTransport(p["path"], p["baud"], spec)
    return SerialTransport(p["path"], DEFAULT_BAUD, spec)
