#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""vg031_bus: several virtual STM32G031 servos (vg031.py) on one emulated
single wire, all in one virtual time, served to one master over TCP like
sim/bus/servo-bus's other backends (raw bytes, or RFC 2217 for the baud).

    vg031_bus.py --ids 1,2,3 --port 0 [--image BOOT.elf] [--app APP.kmfw]
                 [--app-elf APP.elf] [--build-dir DIR] [--baud N]
                 [--flash-dir DIR] [--timeout S] [servo-bus's other options]

servo-bus --backend g031 runs this program with its own arguments. Each
servo runs the unmodified bootloader and application images of the
stm32g031 preset (default build/stm32g031/boards/stm32g031:
km-boot-stm32g031.elf, km-servo-app-stm32g031.kmfw in the application
region, km-servo-app-stm32g031.elf for its WFI sites); --image naming an
application ELF (one with km_app_poll: km-servo-stm32g031.elf) runs that
stand-alone image at 0x08000000 instead. It gets its ID over
the protocol, alone on its wire, before it joins the bus: ping ID 0, write
0x0F = ID, ping the new ID (docs/protocol.md §5.1).

The wire is modelled in virtual time: a byte a servo sends reaches every
other servo at its stop bit (decoded at the receiver's own bit time,
g031_wire.py), and the master's bytes go on the wire at the virtual time
they arrive. The servos' answer slots (super-ID, 0x82) therefore keep
their order exactly, however loaded the host: --slot-floor-us has nothing
to do and is only logged. Virtual time follows real time where the
emulator is fast enough and lags behind it where it is not (it never runs
ahead, so an idle bus does not spin); answers go to the master in the
order of their start bits.

Each chunk of the master's bytes goes on the wire back to back from the
virtual time it arrives (a master writes a frame at once); while more than
20 ms of them wait for the wire, the bus reads no more from the client
(TCP then holds its writes back, as a serial port's full buffer does); --gap-floor-us
is accepted and has no effect: the unmodified image keeps the parser's
real gap rule, and virtual time never runs faster than real time, so a
host stall inside a frame is no longer on the wire than in real time.

--monitor-dir DIR: each servo gets DIR/servo-ID.sock, a Unix socket that
answers like QEMU's human monitor to the one command tools/servo-update
--resets sends, "system_reset": a reset from the NRST pin (RM0444 §5.1.2:
core and peripherals to their reset values, SRAM and flash kept, PINRSTF).

--clock-file PATH: the bus's virtual time in PATH (16 bytes: the time in
little-endian ns, then the master's hold), for a master that counts its
timeouts in it (sim/g031/vclock.py);
the wire stops at the end of the master's sleep until its next bytes, so
its pauses on the wire are exact however slowly the host runs it.

--flash-dir DIR: each servo's whole 64 KiB flash in DIR/servo-ID.flash,
read at start (a servo that already answers on its ID is not written
again) and written back when the bus stops (SIGTERM, SIGINT, client gone).

KM_G031_TRACE=1 in the environment: every byte on the wire and every flash
operation, with its virtual time, on stderr.

stdout: exactly one line "ready 127.0.0.1:PORT" once every servo answers
on its ID; everything else on stderr. Exit 0 after SIGTERM / SIGINT, 1 when
a servo cannot be provisioned, 2 for usage errors and missing images."""
import argparse
import faulthandler
import os
import selectors
import signal
import socket
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
import g031_deps  # noqa: E402
import vclock  # noqa: E402

REPO = os.path.dirname(os.path.dirname(HERE))
IMAGES = "boards/stm32g031"
BUILD_DEFAULT = "build/stm32g031"
HOST = "127.0.0.1"
QUANTUM_NS = 50_000     # the servos advance together in steps of this much virtual time
BACKLOG_NS = 20_000_000  # the master's bytes queued on the wire ahead of now, at most
HOLD_REAL_S = 0.5       # a master's hold kept at most this long in real time without its bytes
STOP = []
TRACE = bool(os.environ.get("KM_G031_TRACE"))


def log(msg):
    print("servo-bus: g031: " + msg, file=sys.stderr, flush=True)


def frame(servo_id, cmd, adr=None, params=b""):
    """A command frame with its checksum (docs/protocol.md §2)."""
    body = bytes([servo_id, 2 + len(params) + (adr is not None), cmd])
    body += (bytes([adr]) if adr is not None else b"") + params
    return b"\xf9\xff" + body + bytes([~sum(body) & 0xFF])


def parse_args(argv):
    """servo-bus's command line, with the options that mean something here."""
    ap = argparse.ArgumentParser(prog="servo-bus --backend g031", description=__doc__.split("\n\n")[0])
    ap.add_argument("--ids", required=True)
    ap.add_argument("--port", required=True, type=int)
    ap.add_argument("--backend", default="g031")
    ap.add_argument("--baud", type=int, default=115200)
    ap.add_argument("--image", help="the bootloader ELF (km-boot-stm32g031.elf)")
    ap.add_argument("--app", help="the application update image (.kmfw)")
    ap.add_argument("--app-elf", help="the application ELF")
    ap.add_argument("--build-dir")
    ap.add_argument("--gap-floor-us", type=int, default=0)
    ap.add_argument("--slot-floor-us", type=int)
    ap.add_argument("--product")
    ap.add_argument("--scenario", action="append", default=[])
    ap.add_argument("--qemu-arg", action="append", default=[])
    ap.add_argument("--monitor-dir")
    ap.add_argument("--flash-dir")
    ap.add_argument("--clock-file", help="keep the virtual time here for the master (sim/g031/vclock.py)")
    ap.add_argument("--plant", default="realistic", choices=("realistic", "ideal", "none"),
                    help="each servo's plant (sim/plant configuration), or none: fixed sensor inputs")
    ap.add_argument("--timeout", type=float, default=10.0)
    ap.add_argument("--realtime", action="store_true")
    ap.add_argument("--no-realtime", action="store_true")
    return ap.parse_args(argv)


def is_application(elf_path):
    """True for an application linked stand-alone at 0x08000000 (it has the
    main loop, km_app_poll), False for the bootloader."""
    import vg031
    try:
        vg031.symbol(elf_path, "km_app_poll")
        return True
    except KeyError:
        return False


def image_paths(a):
    """(boot ELF, app .kmfw, app ELF) from the options and the build tree;
    (None, None, ELF) when --image is a stand-alone application."""
    build = os.path.join(REPO, a.build_dir or os.environ.get("KM_BUILD_STM32G031") or BUILD_DEFAULT, IMAGES)
    if a.image and os.path.isfile(a.image) and is_application(a.image):
        return None, None, a.image
    boot = a.image or os.path.join(build, "km-boot-stm32g031.elf")
    folder = os.path.dirname(boot)
    app = a.app or os.path.join(folder, "km-servo-app-stm32g031.kmfw")
    app_elf = a.app_elf or os.path.join(folder, "km-servo-app-stm32g031.elf")
    return boot, app, app_elf


def refused_options(a):
    """The reason an option cannot apply to the virtual G031, or None."""
    if a.qemu_arg:
        return "--qemu-arg is for the qemu backend only"
    if a.monitor_dir and not os.path.isdir(a.monitor_dir):
        return "--monitor-dir: %s is not a directory" % a.monitor_dir
    if a.product not in (None, "pot"):
        return "--product %s: the stm32g031 image is the potentiometer product" % a.product
    if a.scenario and a.plant == "none":
        return "--scenario needs a plant (--plant realistic or ideal)"
    if a.realtime:
        return "--realtime: the virtual bus keeps slots in virtual time and needs no SCHED_FIFO"
    return None


class Line:
    """The master's side of the wire for pyserial's RFC 2217 PortManager:
    the baud a client sets, like a serial port's."""

    def __init__(self, baud):
        self.baudrate = baud
        self.bytesize, self.parity, self.stopbits = 8, "N", 1
        self.xonxoff = self.rtscts = self.break_condition = False
        self.dtr = self.rts = True
        self.cts = self.dsr = self.ri = self.cd = False

    def reset_input_buffer(self):
        """Nothing is held back from the client."""

    def reset_output_buffer(self):
        """Nothing is held back for the servos."""


class Servo:
    """One virtual G031 on the bus, with the file that keeps its flash."""

    def __init__(self, dev_id, images, flash_dir, plant_config="realistic", scenario=()):
        import vg031
        import g031_plant
        boot, app, app_elf = images
        self.id = dev_id
        self.flash_file = os.path.join(flash_dir, "servo-%d.flash" % dev_id) if flash_dir else None
        image = None
        if self.flash_file and os.path.exists(self.flash_file):
            with open(self.flash_file, "rb") as f:
                image = f.read()
            if len(image) != vg031.P.FLASH_SIZE:
                log("servo id %d: %s is not a 64 KiB flash image: images flashed again" % (dev_id, self.flash_file))
                image = None
        self.kept = image is not None
        plant = None if plant_config == "none" else g031_plant.Plant(plant_config, scenario)
        flash = image or (vg031.flash_from_images(boot, app) if boot else vg031.flash_from_images(elf=app_elf))
        self.m = vg031.Machine(flash, elves=[p for p in (boot, app_elf) if p], plant=plant)
        self.faults_seen = self.resets_seen = self.ops_seen = 0

    def exchange(self, data, wait_ns):
        """Alone on its wire: sends `data` at the master's 115200 baud (a
        fresh servo's rate, docs/protocol.md §1), returns what it answers."""
        self.m.take_output()
        end = self.m.send(data, 115200)
        self.m.run_until(end + wait_ns)
        return bytes(b for _t, b in self.m.take_output())

    def answers(self, dev_id):
        """True when a ping to dev_id is answered (docs/protocol.md §4)."""
        out = self.exchange(frame(dev_id, 0x01), 5_000_000)
        return out[:3] == bytes([0xF9, 0xF5, dev_id])

    def provision(self, timeout_s):
        """Gives the servo its ID over the protocol, in virtual time (boot
        included); False when it never answers."""
        limit = self.m.now + int(timeout_s * 1e9)
        if self.kept and self.answers(self.id):
            return True
        while not self.answers(0):
            if self.m.now > limit:
                return False
        self.exchange(frame(0, 0x03, 0x0F, bytes([self.id])), 200_000_000)
        return self.answers(self.id)

    def save(self):
        """Writes the flash back to its file (--flash-dir)."""
        if self.flash_file:
            with open(self.flash_file, "wb") as f:
                f.write(bytes(self.m.flash))

    def report_faults(self):
        """Logs faults and resets the core took since the last call, and
        with KM_G031_TRACE set its flash operations."""
        for when, kind, pc in self.m.faults[self.faults_seen:]:
            log("servo id %d: %s at pc 0x%08x, %.3f ms" % (self.id, kind, pc, when / 1e6))
        for when, reason in self.m.resets[self.resets_seen:]:
            log("servo id %d: %s reset, %.3f ms" % (self.id, reason, when / 1e6))
        if TRACE:
            for when, kind, where in self.m.flashc.ops[self.ops_seen:]:
                log("trace %.3f ms: servo id %d flash %s %s" % (when / 1e6, self.id, kind, where))
        self.faults_seen, self.resets_seen, self.ops_seen = (
            len(self.m.faults), len(self.m.resets), len(self.m.flashc.ops))


class Bus:
    """The shared wire in virtual time, one TCP client as the master."""

    def __init__(self, server, servos, baud, clock_file=None):
        self.server, self.servos = server, servos
        self.clock = vclock.create(clock_file) if clock_file else None
        self.baud = baud
        self.line = Line(baud)
        self.client, self.rfc2217, self.fresh = None, None, False
        self.client_out = bytearray()
        self.now = max(s.m.now for s in servos)
        for s in servos:
            s.m.run_until(self.now)
            s.m.take_output()
        self.master_free = self.now      # end of the master's last byte on the wire
        self.released = 0                # the master's latest hold that no longer stops the bus
        self.held_since = None           # real time the bus reached the master's hold
        self.sel = selectors.DefaultSelector()
        self.sel.register(server, selectors.EVENT_READ, "server")
        self.anchor = (time.monotonic(), self.now)
        self.started = self.anchor
        if self.clock is not None:
            vclock.publish(self.clock, self.now)

    def _accept(self):
        conn, addr = self.server.accept()
        if self.client is not None:
            try:
                conn.send(b"servo-bus: busy: another client holds the bus\n")
            except OSError:
                pass
            conn.close()
            return
        conn.setblocking(False)
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.client, self.fresh, self.rfc2217 = conn, True, None
        self.line = Line(self.baud)
        self.sel.register(conn, selectors.EVENT_READ, "client")
        log("client connected from %s:%d" % addr)

    def add_monitors(self, monitor_dir):
        """A monitor socket per servo (--monitor-dir)."""
        for s in self.servos:
            path = os.path.join(monitor_dir, "servo-%d.sock" % s.id)
            if os.path.exists(path):
                os.unlink(path)
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            sock.bind(path)
            sock.listen(1)
            sock.setblocking(False)
            self.sel.register(sock, selectors.EVENT_READ, ("monitor", s))

    def _monitor(self, key):
        """A monitor connection or command: "system_reset" resets the servo."""
        kind, servo = key.data
        if kind == "monitor":
            conn, _ = key.fileobj.accept()
            conn.sendall(b"vg031 monitor\r\n(qemu) ")
            self.sel.register(conn, selectors.EVENT_READ, ("command", servo))
            return
        try:
            got = key.fileobj.recv(256)
        except OSError:
            got = b""
        if not got:
            self.sel.unregister(key.fileobj)
            key.fileobj.close()
            return
        if b"system_reset" in got:
            servo.m.request_reset("pin")
        key.fileobj.sendall(b"\r\n(qemu) ")

    def _drop_client(self):
        self.sel.unregister(self.client)
        self.client.close()
        self.client = None
        self.client_out.clear()
        log("client disconnected")

    def write(self, data):
        """PortManager's connection: Telnet/RFC 2217 replies."""
        self.client_out += bytes(data)

    def _from_client(self, chunk):
        if self.fresh:
            self.fresh = False
            if chunk[0] == 0xFF and (len(chunk) == 1 or chunk[1] in (251, 252, 253, 254)):
                import serial.rfc2217
                self.rfc2217 = serial.rfc2217.PortManager(self.line, self)
                log("client speaks RFC 2217")
        start = max(self.now, self.master_free)
        if self.rfc2217 is None:
            self._to_servos(chunk, start)
            return
        for byte in self.rfc2217.filter(chunk):
            start = self._to_servos(byte, start)

    def _to_servos(self, data, start):
        """The master's bytes on the wire from `start` at its baud; returns their end."""
        tx_bit = 1e9 / self.line.baudrate
        if TRACE:
            log("trace %.3f ms: master %s" % (start / 1e6, bytes(data).hex()))
        for byte in data:
            for s in self.servos:
                self._deliver(s, start, byte, tx_bit)
            start += 10 * tx_bit
        self.master_free = start
        return start

    def _deliver(self, servo, start, byte, tx_bit):
        """A byte whose start bit began at `start` reaches one servo's USART."""
        u = servo.m.usart1
        if not u.enabled():
            return
        rx_bit = u.bit_ns()
        got = _decode(byte, tx_bit, rx_bit)
        if got is not None:
            servo.m.wire_in(max(start + 9.5 * rx_bit, servo.m.now + 1), got[0], got[1])

    def _advance(self, until):
        """Every servo to virtual time `until`; their bytes onto the wire."""
        sent = []
        for s in self.servos:
            s.m.run_until(until)
            bit = s.m.usart1.bit_ns()
            sent += [(t, b, bit, s) for t, b in s.m.take_output()]
            s.report_faults()
        self.now = until
        if self.clock is not None:
            vclock.publish(self.clock, until)
        if TRACE and sent:
            log("trace %.3f ms: sent %s" % (until / 1e6, " ".join(
                "%d:%02x@%.3f" % (s.id, b, t / 1e6) for t, b, _bit, s in sorted(sent, key=lambda x: x[0]))))
        for t, byte, bit, src in sorted(sent, key=lambda x: x[0]):
            for s in self.servos:
                if s is not src:
                    self._deliver(s, t, byte, bit)
            got = _decode(byte, bit, 1e9 / self.line.baudrate)
            if self.client is not None and got is not None and not got[1]:
                self.client_out += b"\xff\xff" if got[0] == 0xFF and self.rfc2217 else bytes([got[0]])

    def _wait_s(self):
        """Real seconds to wait before the next quantum: virtual time never
        runs ahead of real time; when it lags, the anchor moves (no sprint)."""
        r0, v0 = self.anchor
        real = time.monotonic()
        ahead = (self.now - v0) / 1e9 - (real - r0)
        if ahead < -0.02:
            self.anchor = (real, self.now)
        return max(0.0, ahead)

    def _service(self, timeout):
        """Socket events: a client, its bytes, our bytes to it."""
        if self.client is not None and self.client_out:
            try:
                n = self.client.send(self.client_out)
                del self.client_out[:n]
            except BlockingIOError:
                pass
            except OSError:
                self._drop_client()
        for key, _mask in self.sel.select(timeout):
            if key.data == "server":
                self._accept()
            elif isinstance(key.data, tuple):
                self._monitor(key)
            elif self.client is not None:
                if self.master_free - self.now > BACKLOG_NS:
                    continue  # the wire is busy: the client waits, as on a serial port whose buffer is full
                try:
                    chunk = self.client.recv(4096)
                except (BlockingIOError, InterruptedError):
                    continue
                except OSError:
                    chunk = b""
                if not chunk:
                    self._drop_client()
                else:
                    self._from_client(chunk)
                    self._release_hold()

    def _release_hold(self):
        """The master spoke (or kept silent too long): a hold the wire has
        reached no longer stops it (a later one, already published, does)."""
        h = vclock.hold(self.clock) if self.clock is not None else 0
        if h <= self.now:
            self.released = max(self.released, h)
        self.held_since = None

    def _limit(self):
        """How far the wire may advance now: the master's hold (the end of
        its sleep) stops it until the master's next bytes, its next hold,
        or HOLD_REAL_S of real time; None: no limit."""
        h = vclock.hold(self.clock) if self.clock is not None else 0
        if h <= self.released:
            return None
        if h < self.now:             # already behind us: nothing to keep
            self.released = h
            return None
        if h > self.now:
            return h
        if self.held_since is None:
            self.held_since = time.monotonic()
        elif time.monotonic() - self.held_since > HOLD_REAL_S:
            self._release_hold()
            return None
        return self.now

    def run(self):
        """Until SIGTERM or SIGINT."""
        while not STOP:
            limit = self._limit()
            held = limit is not None and limit <= self.now
            self._service(0.001 if held else min(self._wait_s(), 0.05))
            if not held and self._wait_s() == 0.0:
                step = self.now + QUANTUM_NS
                self._advance(step if limit is None else min(step, limit))

    def speed(self):
        """Virtual us per real second since the bus started."""
        real = time.monotonic() - self.started[0]
        return (self.now - self.started[1]) / 1e3 / real if real > 0 else 0.0


def _decode(byte, tx_bit, rx_bit):
    import g031_wire
    return g031_wire.decode(byte, tx_bit, rx_bit)


SCENARIO_KEYS = {"supply_mv": 1, "ambient_dc": 2, "load_mnm": 3, "faults": 4, "temp_dc": 5}


def read_scenarios(specs, ids):
    """{ID: [(t_ms, key, value)]} from servo-bus's --scenario [ID=]FILE
    options (lines "T_MS KEY VALUE", boards/sim-common/km_sim_scenario.h);
    ValueError with the line when one is malformed."""
    out = {}
    for spec in specs:
        dev, _, path = spec.rpartition("=")
        events = []
        with open(path) as f:
            for n, line in enumerate(f, 1):
                words = line.split("#", 1)[0].split()
                if not words:
                    continue
                if len(words) != 3 or words[1] not in SCENARIO_KEYS:
                    raise ValueError("%s:%d: expected T_MS KEY VALUE with KEY one of %s"
                                     % (path, n, ", ".join(SCENARIO_KEYS)))
                events.append((int(words[0]), SCENARIO_KEYS[words[1]], int(words[2], 0)))
        for i in ([int(dev)] if dev else ids):
            out[i] = events
    return out


def main(argv=None):
    a = parse_args(sys.argv[1:] if argv is None else argv)
    g031_deps.require()
    why = refused_options(a)
    if why:
        log(why)
        return 2
    try:
        ids = [int(x, 0) for x in a.ids.split(",") if x.strip()]
    except ValueError:
        log("--ids: not a list of IDs: %r" % a.ids)
        return 2
    try:
        scenarios = read_scenarios(a.scenario, ids)
    except (OSError, ValueError) as e:
        log("--scenario: %s" % e)
        return 2
    images = image_paths(a)
    missing = [p for p in images if p and not os.path.isfile(p)]
    if missing:
        log("no image at %s; build it first: cmake --preset stm32g031 && cmake --build --preset stm32g031"
            % ", ".join(missing))
        return 2
    if a.gap_floor_us:
        log("--gap-floor-us %d: no effect, the image keeps the parser's real gap rule" % a.gap_floor_us)
    if a.slot_floor_us:
        log("--slot-floor-us %d: not needed, the wire keeps answer slots in virtual time" % a.slot_floor_us)
    faulthandler.register(signal.SIGUSR1)  # kill -USR1 PID: where the bus is, on stderr
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: STOP.append(1))
    server = socket.socket()
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        server.bind((HOST, a.port))
    except OSError as e:
        log("cannot listen on %s:%d: %s" % (HOST, a.port, e))
        return 2
    server.listen(1)
    server.setblocking(False)
    servos, bus = [], None
    try:
        for dev_id in ids:
            if STOP:
                return 0
            s = Servo(dev_id, images, a.flash_dir, a.plant, scenarios.get(dev_id, ()))
            if not s.provision(a.timeout):
                log("servo id %d: no answer to a ping on ID 0 within %.0f s of virtual time" % (dev_id, a.timeout))
                return 1
            log("servo id %d: on the bus (%.1f ms virtual since power-on)" % (dev_id, s.m.now / 1e6))
            servos.append(s)
        if STOP:
            return 0
        bus = Bus(server, servos, a.baud, a.clock_file)
        if a.monitor_dir:
            bus.add_monitors(a.monitor_dir)
        print("ready %s:%d" % server.getsockname(), flush=True)
        bus.run()
        log("stopping: %.0f virtual us per real second over the run" % bus.speed())
        return 0
    finally:
        if bus is not None and bus.clock is not None:
            vclock.stop(bus.clock)
        for s in servos:
            s.save()
        server.close()


if __name__ == "__main__":
    sys.exit(main())
