#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""UART smoke test for qemu-microbit: runs km-uart-echo-qemu-microbit.elf with
UART0 on a TCP socket and checks RX interrupt + TX + one-shot timer:
banner at boot (boot time = connect -> first byte), then each byte sent
comes back with the tick gap since the previous byte and the timer's
lateness. Prints measurements; exit 0 only if every check passes."""
import socket
import statistics
import struct
import subprocess
import sys
import time
from pathlib import Path

DELAY_US = 500
REPLY = 7


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def recv_exact(sock: socket.socket, n: int, timeout: float) -> bytes:
    sock.settimeout(timeout)
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            raise ConnectionError("QEMU closed the socket")
        data += chunk
    return data


class Checks:
    def __init__(self) -> None:
        self.failed = 0

    def check(self, ok: bool, what: str) -> None:
        print(("PASS " if ok else "FAIL ") + what, flush=True)
        self.failed += 0 if ok else 1


def run(sock: socket.socket, t_connect: float, c: Checks) -> None:
    banner = recv_exact(sock, 4, 5.0)
    boot_ms = (time.monotonic() - t_connect) * 1000
    c.check(banner == b"KMQ\n", f"boot banner {banner!r}")
    print(f"INFO boot to first UART byte {boot_ms:.1f} ms (host clock, from connect)")

    rtts, gaps = [], []
    for i, b in enumerate([0x00, 0x55, 0xAA, 0xFF, 0x7E]):
        if i:
            time.sleep(0.05)
        t0 = time.monotonic()
        sock.sendall(bytes([b]))
        r = recv_exact(sock, REPLY, 5.0)
        rtts.append((time.monotonic() - t0) * 1000)
        byte, dt, late = struct.unpack("<BIH", r)
        c.check(byte == b, f"echo of 0x{b:02x}")
        c.check(late < 20000, f"one-shot {DELAY_US} us after RX fired {late} us late")
        if i:
            gaps.append(dt)
            c.check(40_000 <= dt <= 1_000_000, f"tick gap after a 50 ms pause: {dt} us")

    burst = bytes(range(0x30, 0x38))
    sock.sendall(burst)
    r = recv_exact(sock, REPLY * len(burst), 5.0)
    echoed = bytes(r[k * REPLY] for k in range(len(burst)))
    c.check(echoed == burst, f"burst of {len(burst)} bytes echoed in order")
    dts = [struct.unpack_from("<I", r, k * REPLY + 1)[0] for k in range(1, len(burst))]
    c.check(all(d < 50_000 for d in dts), f"burst tick gaps {dts} us")

    sock.settimeout(0.2)
    try:
        extra = sock.recv(64)
    except socket.timeout:
        extra = b""
    c.check(extra == b"", "no extra bytes (own TX not heard as RX)")
    print(f"INFO round trip per byte (host->guest->host, incl. {DELAY_US} us delay): "
          f"median {statistics.median(rtts):.2f} ms, max {max(rtts):.2f} ms")


def main() -> int:
    if len(sys.argv) != 3:
        print("usage: uart_echo.py <km-uart-echo-qemu-microbit.elf> <timeout_s>", file=sys.stderr)
        return 2
    image, timeout = Path(sys.argv[1]), float(sys.argv[2])
    if not image.is_file():
        print(f"FAIL: {image} not found: build the qemu preset first "
              "(cmake --preset qemu && cmake --build --preset qemu)", file=sys.stderr)
        return 1
    port = free_port()
    cmd = ["qemu-system-arm", "-M", "microbit", "-display", "none", "-monitor", "none",
           "-chardev", f"socket,id=s0,host=127.0.0.1,port={port},server=on,wait=on,nodelay=on",
           "-serial", "chardev:s0", "-kernel", str(image)]
    print(" ".join(cmd), flush=True)
    qemu = subprocess.Popen(cmd)
    c = Checks()
    try:
        deadline = time.monotonic() + timeout
        while True:
            try:
                sock = socket.create_connection(("127.0.0.1", port), timeout=1.0)
                break
            except OSError:
                if time.monotonic() > deadline or qemu.poll() is not None:
                    print("FAIL: could not connect to QEMU's serial socket", file=sys.stderr)
                    return 1
                time.sleep(0.02)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        with sock:
            run(sock, time.monotonic(), c)
    except (OSError, ConnectionError) as e:
        print(f"FAIL: {e}", file=sys.stderr)
        return 1
    finally:
        qemu.terminate()
        try:
            qemu.wait(timeout=5)
        except subprocess.TimeoutExpired:
            qemu.kill()
    print(f"{c.failed} failed")
    return 0 if c.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
