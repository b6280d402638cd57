#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The virtual STM32G031 (sim/g031) running the shipped, unmodified images
of the stm32g031 preset: boot to the main loop, bus answers with their
bytes and delay (docs/protocol.md §2-§5), a stored ID across a system
reset, and the IWDG ending a hung main loop.

    test_vg031_images.py BUILD_DIR/boards/stm32g031
"""
import os
import sys
import unittest
import argparse
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
import g031_deps  # noqa: E402
g031_deps.require()
import vg031  # noqa: E402

IMAGES = None
BAUD = 115200        # a fresh servo's baud (docs/protocol.md §1)
MS = 1_000_000


def frame(servo_id, cmd, adr=None, params=b""):
    """A command frame with its checksum (docs/protocol.md §2)."""
    body = bytes([servo_id, 2 + len(params) + (adr is not None), cmd])
    body += (bytes([adr]) if adr is not None else b"") + params
    return b"\xf9\xff" + body + bytes([~sum(body) & 0xFF])


def boot_and_app(watch_names=("km_app_poll",), check_alignment=False):
    """A machine with the bootloader and the update image of the application."""
    a = argparse.Namespace(boot=os.path.join(IMAGES, "km-boot-stm32g031.elf"),
                           app=os.path.join(IMAGES, "km-servo-app-stm32g031.kmfw"), elf=None,
                           app_elf=os.path.join(IMAGES, "km-servo-app-stm32g031.elf"))
    watch = [vg031.symbol(a.app_elf, n) for n in watch_names]
    return vg031.make(a, watch=watch, check_alignment=check_alignment), watch


def standalone():
    """A fresh machine running the stand-alone servo image: (machine, its
    main loop's poll address, the image's path)."""
    elf = os.path.join(IMAGES, "km-servo-stm32g031.elf")
    poll = vg031.symbol(elf, "km_app_poll")
    m = vg031.make(argparse.Namespace(boot=None, app=None, elf=elf, app_elf=None), watch=[poll])
    return m, poll, elf


def to_main_loop(m, poll, limit_ms=100):
    """Runs until the main loop's poll runs; returns whether it did."""
    return m.run_until(m.now + limit_ms * MS, stop=lambda: bool(m.watches[poll]))


def exchange(m, data, wait_ms=5):
    """Sends a frame, returns (answer bytes, µs from the last stop bit to the first start bit)."""
    m.take_output()
    end = m.send(data, BAUD)
    m.run_until(end + wait_ms * MS)
    out = m.take_output()
    return bytes(b for _t, b in out), ((out[0][0] - end) / 1000 if out else None)


def stored_snapshots(m, key=0x0F):
    """Value of `key` in each confirmed snapshot in the emulated store pages
    (docs/store.md "On-flash format", 8-byte cells): {key: value} of the
    one with the highest generation, {} if none."""
    elf = os.path.join(IMAGES, "km-servo-app-stm32g031.elf")
    start = vg031.symbol(elf, "__km_store_start") - 0x08000000
    size = vg031.symbol(elf, "__km_store_end") - 0x08000000 - start
    best = None
    for page in range(start, start + size, 2048):
        d = bytes(m.flash[page:page + 2048])
        count = d[1]
        if d[0] != 0x53 or not 0 < count <= 32:
            continue
        body = (12 + 5 * count + 4 + 7) // 8 * 8
        crc_ok = zlib.crc32(d[:body - 4]) == int.from_bytes(d[body - 4:body], "little")
        if not crc_ok or d[body:body + 16] != bytes(16):   # commit cell and K
            continue
        gen = int.from_bytes(d[4:8], "little")
        entries = {d[12 + 5 * i]: int.from_bytes(d[13 + 5 * i:17 + 5 * i], "little") for i in range(count)}
        if key in entries and (best is None or gen > best[0]):
            best = (gen, entries[key])
    return {} if best is None else {key: best[1]}


class Images(unittest.TestCase):
    def test_standalone_image_reaches_main_loop(self):
        m, poll, elf = standalone()
        self.assertTrue(to_main_loop(m, poll), "km_app_poll never ran: %s %s" % (m.faults, m.resets))
        t, instr = m.watches[poll][0]
        print("stand-alone: main loop after %d instructions, %.3f ms virtual" % (instr, t / 1e6))
        self.assertEqual(m.faults, [])

    def test_bootloader_starts_app_to_main_loop(self):
        m, (poll,) = boot_and_app()
        self.assertTrue(to_main_loop(m, poll), "km_app_poll never ran: %s %s" % (m.faults, m.resets))
        t, instr = m.watches[poll][0]
        print("boot+app: main loop after %d instructions, %.3f ms virtual" % (instr, t / 1e6))
        self.assertEqual((m.faults, m.resets), ([], []))

    def test_update_mode_bootloader_sleeps_between_bytes(self):
        """The bootloader alone (no application: update mode at ID 0 and
        115200, firmware/update/km_boot_address.h) sleeps in WFI between
        bytes (km_bootb_wait, the 64 KiB build) and still answers: a quiet
        100 ms runs a few of its 10 ms wake-ups, where a polling loop at
        16 MHz runs 1.6 million instructions; a ping is answered after it."""
        boot = os.path.join(IMAGES, "km-boot-stm32g031.elf")
        m = vg031.make(argparse.Namespace(boot=boot, app=None, elf=None, app_elf=None))
        m.run_until(50 * MS)
        answer, _ = exchange(m, frame(0, 0x01))
        self.assertEqual(answer[:3], bytes.fromhex("F9F500"), "update mode, ID 0: %s" % answer.hex(" "))
        before = m.instructions
        m.run_until(m.now + 100 * MS)
        quiet = m.instructions - before
        answer, delay = exchange(m, frame(0, 0x01))
        print("bootloader in update mode: %d instructions in a quiet 100 ms; ping answered %s, "
              "%.1f us after the stop bit" % (quiet, answer.hex(" "), delay or -1))
        self.assertLess(quiet, 100_000)
        self.assertEqual(answer[:3], bytes.fromhex("F9F500"), answer.hex(" "))
        self.assertEqual((m.faults, m.resets), ([], []))

    def test_master_pause_exact_on_the_wire(self):
        """A master on the bus's virtual time (vclock) that the host runs
        late: it sleeps until frame A's time, is held up 0.3 s of real time
        after waking, sends A, sleeps until A's end + 2 ms and sends B. On
        the wire B must start 2 ms after A's last stop bit, as the master
        asked (kmx update's pause after a broadcast block, docs/update.md
        §4); with the wire running on while the master was held up, A went
        out late and B closer behind it (down to gap 0: the bootloader,
        programming A's block, loses B)."""
        import socket
        import subprocess
        import tempfile
        import vclock
        with tempfile.TemporaryDirectory() as tmp:
            clock_path = os.path.join(tmp, "clock")
            err = open(os.path.join(tmp, "stderr"), "w+")
            bus = subprocess.Popen([sys.executable, os.path.join(HERE, "..", "..", "sim", "g031", "vg031_bus.py"),
                                    "--ids", "1", "--port", "0", "--plant", "none", "--clock-file", clock_path,
                                    "--image", os.path.join(IMAGES, "km-servo-stm32g031.elf")],
                                   stdout=subprocess.PIPE, stderr=err, text=True,
                                   env=dict(os.environ, KM_G031_TRACE="1"))
            try:
                host, port = bus.stdout.readline().split()[1].rsplit(":", 1)
                clock = vclock.Clock(clock_path)
                conn = socket.create_connection((host, int(port)))
                a, b = frame(9, 0x01), frame(9, 0x02, 0x0B)   # to an ID nobody has: no answers
                # kmx update's pace(): the next frame's time from the clock,
                # a sleep until it, the frame; the pause counted from there.
                wire_free = clock.ns() + 10 * MS
                clock.sleep((wire_free - clock.ns()) / 1e9)
                vclock.real_sleep(0.3)
                conn.sendall(a)
                wire_free += len(a) * 10 * 1e9 / BAUD + 2 * MS
                clock.sleep(max(0, wire_free - clock.ns()) / 1e9)
                conn.sendall(b)
                clock.sleep(0.01)
                conn.close()
            finally:
                bus.terminate()
                bus.wait(30)
            err.seek(0)
            chunks = [(float(ln.split(" ms: master ")[0].split()[-1]), bytes.fromhex(ln.split(" ms: master ")[1].split()[0]))
                      for ln in err if " ms: master " in ln]
        starts = {}   # each frame's first start bit on the wire (several may share a chunk), us
        for t_ms, data in chunks:
            for f in (a, b):
                if f in data:
                    starts[f] = t_ms * 1000 + data.index(f) * 10 * 1e6 / BAUD
        gap_us = starts[b] - starts[a] - len(a) * 10 * 1e6 / BAUD
        print("master paused 2000 us after frame A; on the wire: %.1f us" % gap_us)
        self.assertAlmostEqual(gap_us, 2000, delta=60)

    def test_ping_and_register_read_answered(self):
        m, (poll,) = boot_and_app()
        self.assertTrue(to_main_loop(m, poll))
        m.run_until(m.now + 2 * MS)
        answer, delay = exchange(m, frame(0, 0x01))
        self.assertEqual(len(answer), 6, answer.hex(" "))
        self.assertEqual(answer[:4], bytes.fromhex("F9F50002"))
        self.assertEqual(answer[5], ~sum(answer[2:5]) & 0xFF)
        # Bit 4 (hardware fault, 0x35 bit 2: the NTC read before the first
        # ADC scan completed) is the one bit allowed: docs/virtual-g031.md.
        self.assertEqual(answer[4] & ~0x10, 0, answer.hex(" "))
        print("ping answer %s, %.1f us after the stop bit" % (answer.hex(" "), delay))
        self.assertTrue(50 <= delay <= 2000, delay)
        version, delay = exchange(m, frame(0, 0x02, 0x0B))
        self.assertEqual(version, bytes.fromhex("F9F50007020B00000205E4"))

    def test_register_write_survives_system_reset(self):
        m, (poll,) = boot_and_app()
        self.assertTrue(to_main_loop(m, poll))
        m.run_until(m.now + 2 * MS)
        # ID 0 -> 7 (persisted; a write answers only at response level 1,
        # docs/protocol.md §3). The session's first commit on blank flash
        # erases all three store pages (docs/store.md "Commit"): 3 x 22 ms
        # in the model, so the ping waits for it.
        self.assertEqual(exchange(m, frame(0, 0x03, 0x0F, b"\x07"), wait_ms=200)[0], b"")
        answer, _ = exchange(m, frame(7, 0x01))
        self.assertEqual(answer[:4], bytes.fromhex("F9F50702"), answer.hex(" "))
        self.assertEqual(answer[4] & 0x40, 0, "write refused (status bit 6): " + answer.hex(" "))
        self.assertEqual(stored_snapshots(m), {0x0F: 7}, "the store's pages do not hold ID 7")
        exchange(m, frame(7, 0x03, 0x02, b"\xe1\xe2\xe3\xe4"), wait_ms=1)  # restart
        self.assertTrue(m.run_until(m.now + 200 * MS, stop=lambda: bool(m.resets)), "no reset")
        self.assertEqual(m.resets[0][1], "sysresetreq")
        hits = len(m.watches[poll])
        self.assertTrue(m.run_until(m.now + 200 * MS, stop=lambda: len(m.watches[poll]) > hits))
        m.run_until(m.now + 2 * MS)
        answer, _ = exchange(m, frame(7, 0x01))
        self.assertEqual(answer[:4], bytes.fromhex("F9F50702"), answer.hex(" "))
        self.assertEqual(exchange(m, frame(0, 0x01))[0], b"")

    def test_no_unaligned_access_through_boot_and_bus(self):
        # ARMv6-M A3.2.1: the M0+ faults on an unaligned halfword or word
        # access; the machine checks every RAM and flash access for it here.
        m, (poll,) = boot_and_app(check_alignment=True)
        self.assertTrue(to_main_loop(m, poll), "km_app_poll never ran: %s" % (m.faults,))
        m.run_until(m.now + 2 * MS)
        self.assertEqual(exchange(m, frame(0, 0x01))[0][:4], bytes.fromhex("F9F50002"))
        self.assertEqual(exchange(m, frame(0, 0x02, 0x0B))[0][:4], bytes.fromhex("F9F50007"))
        self.assertEqual(exchange(m, frame(0, 0x03, 0x0F, b"\x07"), wait_ms=200)[0], b"")
        exchange(m, frame(7, 0x03, 0x02, b"\xe1\xe2\xe3\xe4"), wait_ms=1)
        self.assertTrue(m.run_until(m.now + 200 * MS, stop=lambda: bool(m.resets)), "no reset")
        m.run_until(m.now + 60 * MS)
        self.assertEqual(exchange(m, frame(7, 0x01))[0][:4], bytes.fromhex("F9F50702"))
        self.assertEqual(m.faults, [])

    def test_first_sensor_read_after_a_full_adc_scan(self):
        # The start-up race: km_hal_sensors_read before the ADC's first
        # full scan (4 channels x 16 x (160.5 + 12.5) ADC cycles at 32 MHz,
        # RM0444 §15.5) would see the zeroed DMA buffer: position, voltage
        # and NTC at a rail (0x35 bits 5, 3, 2).
        # The buffer is the DMA target s_samples (boards/stm32g031/adc.c);
        # the functions around it are inlined (LTO), so the first CPU load
        # from it is watched, against the ADSTART write the ADC model saw.
        from unicorn import UC_HOOK_MEM_READ
        elf = os.path.join(IMAGES, "km-servo-app-stm32g031.elf")
        samples = vg031.symbol(elf, "s_samples")
        m, _ = boot_and_app()
        first_read = []
        m.uc.hook_add(UC_HOOK_MEM_READ, lambda *a: first_read or first_read.append(m.now), None,
                      samples, samples + 7)
        self.assertTrue(m.run_until(m.now + 100 * MS, stop=lambda: bool(first_read)), "s_samples never read")
        self.assertIsNotNone(m.adc.started_at, "ADSTART never written")
        scan_ns = 4 * 16 * (160.5 + 12.5) * 1e9 / 32e6
        gap = first_read[0] - m.adc.started_at
        print("first sensor read %.3f ms after ADSTART (a full scan: %.3f ms)" % (gap / 1e6, scan_ns / 1e6))
        self.assertGreater(gap, scan_ns)
        m.run_until(m.now + 2 * MS)
        faults, _ = exchange(m, frame(0, 0x02, 0x35))
        self.assertEqual(faults[:6], bytes.fromhex("F9F500040235"), faults.hex(" "))
        self.assertEqual(faults[6], 0, "sensor faults at power-on: 0x35 = %#x" % faults[6])

    def test_received_byte_reaches_rx_queue(self):
        # Interrupt latency from RXNE (the middle of the stop bit, RM0444
        # §33.5.6) to km_rx_queue_push's entry, per byte of a ping; each
        # byte must be in the queue before the next one completes. Virtual
        # time at CPI 1 with exception entry taken in no time: silicon adds
        # the M0+'s 15-cycle entry and its wait states.
        m, (poll, push) = boot_and_app(("km_app_poll", "ISR_rx_byte"))  # the app's RX handler: queue push
        self.assertTrue(to_main_loop(m, poll))
        m.run_until(m.now + 2 * MS)
        before = len(m.watches[push])
        start = m.now
        bit = 1e9 / BAUD
        m.send(frame(0, 0x01), BAUD)
        m.run_until(start + 2 * MS)
        pushes = [t for t, _i in m.watches[push][before:]]
        rxne = [start + (10 * k + 9.5) * bit for k in range(6)]
        self.assertGreaterEqual(len(pushes), 6, "bytes pushed: %d of 6" % len(pushes))
        lat = [(p - r) / 1000 for p, r in zip(pushes, rxne)]
        print("RXNE -> ISR_rx_byte (RX queue push): %s us" % ", ".join("%.2f" % x for x in lat))
        for k, x in enumerate(lat):
            # From sleep-on-exit the core wakes at RXNE and enters at once:
            # 0, give or take the float rounding of the bit times (1 ns).
            self.assertTrue(-0.001 <= x < 10 * bit / 1000, "byte %d: %.4f us" % (k, x))

    def test_byte_inside_a_frame_runs_no_main_loop(self):
        # docs/benchmarks.md "Per byte": a byte that does not end a frame
        # costs its receive interrupt alone: taken from sleep, the handler
        # returns into sleep (SCR.SLEEPONEXIT, ARMv6-M B3.2.7) without a
        # Thread mode instruction; a frame's last byte returns to the main
        # loop, which parses it. Frames for another servo and another
        # servo's answer (docs/protocol.md §2): no answer, no TX interrupt.
        m, (poll,) = boot_and_app()
        self.assertTrue(to_main_loop(m, poll))
        m.run_until(m.now + 5 * MS)
        usart1 = 16 + 27
        state = {"slept": False, "from_sleep": False}
        returns = []   # (entered from sleep, returned into sleep) per USART1 return to Thread mode
        sleep, enter, leave = m._sleep, m._enter, m._exit

        def noting_sleep():
            state["slept"] = True
            return sleep()

        def noting_enter(exc, ret_pc):
            if exc == usart1 and not m.active:
                state["from_sleep"] = state["slept"]
            state["slept"] = False
            return enter(exc, ret_pc)

        def noting_exit(exc_return):
            last = m.active == [usart1]
            asleep = leave(exc_return)
            if last:
                returns.append((state["from_sleep"], asleep))
            return asleep
        m._sleep, m._enter, m._exit = noting_sleep, noting_enter, noting_exit
        frames = [frame(5, 0x02, 0x38, b"\x02"), b"\xf9\xf5\x05\x04\x00\x10\x27\xbf",
                  frame(7, 0x03, 0x2a, bytes(range(1, 30)))]
        for f in frames * 2:
            before = len(returns)
            m.run_until(m.send(f, BAUD) + 3 * MS)
            got = returns[before:]
            self.assertEqual(len(got), len(f), "one receive interrupt per byte of %s" % f.hex())
            inner = [slept for from_sleep, slept in got[:-1] if from_sleep]
            self.assertGreaterEqual(len(inner), len(f) - 3, "bytes taken from sleep: %s" % got)
            self.assertTrue(all(inner), "a byte inside %s returned to the main loop: %s" % (f.hex(), got))
            self.assertFalse(got[-1][1], "the last byte of %s did not wake the main loop" % f.hex())

    def test_tick_inside_a_frame_leaves_only_a_short_rest_queued(self):
        # docs/benchmarks.md "Control tick": a control tick's wake-up that
        # falls inside a frame still arriving leaves its bytes in the receive
        # queue when what is queued plus what is still to come is at most
        # KM_APP_RX_DEFER_MAX (12) bytes: the frame's end parses them in one
        # run. A longer rest is parsed at the tick, so the frame's end parses
        # little. Checked at each tick's start (prv_control_tick, after the
        # wake-up's drain): the queue's consumer index behind its producer,
        # or caught up; the frames after them answered as usual.
        from unicorn import UC_HOOK_CODE
        m, poll, elf = standalone()
        self.assertTrue(to_main_loop(m, poll))
        m.run_until(m.now + 5 * MS)
        from elftools.elf.elffile import ELFFile
        with open(elf, "rb") as f:
            rx = [(sym["st_value"], sym["st_size"]) for sym in ELFFile(f).get_section_by_name(".symtab").iter_symbols()
                  if sym.name.split(".")[0] == "s_rx" and sym["st_size"] > 600]
        self.assertEqual(len(rx), 1, "the receive state s_rx (tracker, then queue) not found: %s" % rx)
        head_at = rx[0][0] + 12     # km_rx_track_t: 3 words; then the queue's head, tail
        ticks = []                  # (time, bytes queued) at each tick's start

        def at_tick(uc, _addr, _size, _user):
            head, tail = (int.from_bytes(bytes(uc.mem_read(head_at + i, 4)), "little") for i in (0, 4))
            ticks.append((m.now, (head - tail) & 0xFFFFFFFF))
        tick_fn = vg031.symbol(elf, "prv_control_tick")
        m.uc.hook_add(UC_HOOK_CODE, at_tick, None, tick_fn, tick_fn)
        # A 9-byte frame (another servo's 0x68: no answer), sent at ten phases
        # of the tick: every tick inside one finds its bytes still queued.
        short_inside = []
        for k in range(10):
            m.run_until(m.now + 1 * MS + k * MS // 10)
            start = m.now
            end = m.send(frame(7, 0x03, 0x68, b"\x10\x00"), BAUD)
            m.run_until(end + 2 * MS)
            short_inside += [q for t, q in ticks if start + 0.1 * MS < t < end - 0.05 * MS]
        # A 35-byte frame (3 ms at 115200): a tick with 13 or more bytes
        # still to come (> 1.2 ms before the end) parses what is queued.
        start = m.now
        end = m.send(frame(7, 0x03, 0x2A, bytes(range(1, 30))), BAUD)
        m.run_until(end + 3 * MS)
        long_early = [q for t, q in ticks if start + 0.2 * MS < t < end - 1.3 * MS]
        after = [q for t, q in ticks if t > end + 0.5 * MS]
        print("bytes queued at each tick's start: inside the short frames %s, early in the long frame %s, after"
              " it %s" % (short_inside, long_early, after))
        self.assertGreaterEqual(len(short_inside), 1, "no tick inside a short frame")
        self.assertTrue(all(q > 0 for q in short_inside), "a tick inside a short frame parsed it: %s" % short_inside)
        self.assertGreaterEqual(len(long_early), 1, "no tick early in the long frame")
        self.assertTrue(all(q == 0 for q in long_early), "a tick left a long frame's rest queued: %s" % long_early)
        self.assertTrue(after and all(q == 0 for q in after), "bytes left queued after the frame: %s" % after)
        answer, delay = exchange(m, frame(0, 0x02, 0x0B))
        self.assertEqual(answer, bytes.fromhex("F9F50007020B00000205E4"))
        self.assertTrue(50 <= delay <= 2000, delay)

    def test_framing_error_drops_its_frame_then_bytes_flow(self):
        # A byte received with FE (RM0444 §33.5.6: the data still reaches
        # RDR) is handed over as after a loss: the parser drops the frame it
        # was in (no answer), and the bytes after it take the receive fast
        # path again (the next ping is answered). docs/protocol.md §2.
        m, (poll,) = boot_and_app()
        self.assertTrue(to_main_loop(m, poll))
        m.run_until(m.now + 5 * MS)
        ping = frame(0, 0x01)
        m.take_output()
        bit = 1e9 / BAUD
        t = m.now
        for k, byte in enumerate(ping):
            m.wire_in(t + (10 * k + 9.5) * bit, byte, framing_error=(k == 3))
        m.run_until(t + 10 * len(ping) * bit + 5 * MS)
        self.assertEqual(m.take_output(), [], "a frame with a framing error was answered")
        for _ in range(2):
            self.assertEqual(exchange(m, ping)[0][:4], bytes.fromhex("F9F50002"))

    def test_hung_main_loop_ends_in_iwdg_reset(self):
        m, (poll,) = boot_and_app()
        self.assertTrue(to_main_loop(m, poll))
        # Past the 1 s after which the application confirms its start to the
        # bootloader (docs/update.md §3a): the reset below is not a failed trial.
        m.run_until(m.now + 1100 * MS)
        self.assertEqual(exchange(m, frame(0, 0x01))[0][:4], bytes.fromhex("F9F50002"))
        m.hang()
        slice_ns, m.slice_ns = m.slice_ns, 100_000
        hung_at = m.now
        self.assertTrue(m.run_until(m.now + 2000 * MS, stop=lambda: bool(m.resets)), "no reset")
        when, why = m.resets[0]
        self.assertEqual(why, "iwdg")
        # 500 ms requested, LSI 32 kHz (km_hal_watchdog_start's rounding).
        self.assertTrue(400 * MS <= when - hung_at <= 600 * MS, (when - hung_at) / MS)
        self.assertTrue(m.rcc.read(0x60, m.now) & (1 << 29), "IWDGRSTF not set")
        m.slice_ns = slice_ns
        m.watches[poll].clear()   # (a watch keeps its first 1000 hits)
        self.assertTrue(m.run_until(m.now + 200 * MS, stop=lambda: bool(m.watches[poll])),
                        "no main loop after the IWDG reset")
        m.run_until(m.now + 2 * MS)
        answer, delay = exchange(m, frame(0, 0x01))
        print("IWDG reset %.1f ms after the hang; ping answered %.1f us after its stop bit, %.1f ms after "
              "the reset" % ((when - hung_at) / MS, delay or -1, (m.now - when) / MS))
        self.assertEqual(answer[:4], bytes.fromhex("F9F50002"), "no answer after the IWDG reset")

    def test_hardfault_frees_bridge_and_leaves_record(self):
        # boards/stm32g031/fault.c: HardFault_Handler -> g0_fault_stop: the
        # bridge's inputs to low outputs, TIM3's outputs off, the record in
        # .noinit SRAM, SYSRESETREQ; the next boot keeps it in g0_last_fault.
        m, poll, elf = standalone()
        self.assertTrue(to_main_loop(m, poll))
        m.run_until(m.now + 2 * MS)
        exchange(m, frame(0, 0x03, 0x64, b"\x01"))           # torque on: the bridge holds
        m.run_until(m.now + 20 * MS)
        moder = m.gpioa.r[0x00]
        self.assertEqual(((moder >> 12) & 3, (moder >> 14) & 3), (2, 2), "PA6/PA7 not TIM3's outputs")
        self.assertNotEqual(m.tim3.r[0x20], 0, "TIM3 CCER: no output enabled before the fault")
        free_at_request = []    # the bridge's state when the core asks for the reset
        request_reset = m.request_reset
        m.request_reset = lambda why: (free_at_request.append(bridge_free(m)), request_reset(why))
        at = m.bad_load()
        self.assertTrue(m.run_until(m.now + 10 * MS, stop=lambda: bool(m.resets)), "no reset after the fault")
        self.assertEqual(free_at_request, [True], "bridge not freed before the reset request")
        self.assertEqual(m.resets[0][1], "sysresetreq")
        self.assertEqual(m.faults[0][1], "unmapped")
        hits = len(m.watches[poll])
        self.assertTrue(m.run_until(m.now + 200 * MS, stop=lambda: len(m.watches[poll]) > hits))
        m.run_until(m.now + 2 * MS)
        # The record the handler wrote: kind 3, the load's PC, LR, check =
        # ~(magic ^ kind ^ pc ^ lr); the boot that read it zeroed its magic only.
        ram = bytes(m.uc.mem_read(0x20000000, 8192))
        kind_pc = (3).to_bytes(4, "little") + at.to_bytes(4, "little")
        found = ram.find(kind_pc)
        self.assertGreaterEqual(found, 4, "no fault record (kind 3, pc 0x%08x) in SRAM" % at)
        lr, check = (int.from_bytes(ram[found + i:found + i + 4], "little") for i in (8, 12))
        self.assertEqual(check, ~(0xFA017EC0 ^ 3 ^ at ^ lr) & 0xFFFFFFFF, "record check word")
        # ... and the next boot reports a fault reset over 0x7F (KM_RESET_FAULT = 4).
        answer, _ = exchange(m, frame(0, 0x7F, 0x02))
        print("HardFault at 0x%08x: bridge free at the reset request, reset %.3f ms after the fault; "
              "record pc 0x%08x lr 0x%08x; 0x7F reset cause answer %s"
              % (at, (m.resets[0][0] - m.faults[0][0]) / MS, at, lr, answer.hex(" ")))
        self.assertEqual(answer[:7], bytes.fromhex("F9F500047F0204"), answer.hex(" "))

    def test_stack_guard_written_resets_with_record(self):
        # boards/stm32g031/fault.c: SysTick checks the stack guard band four
        # words a millisecond, the whole 32-word band every 8 ms; a word of
        # it overwritten (its first, one inside, its last) stops the servo:
        # record kind G0_FAULT_STACK_GUARD (0x100), SYSRESETREQ, and the next
        # boot reports a fault reset over 0x7F. Written 300 ms after boot, once
        # the blank store's idle format is over: an erase delays the reset
        # by its own length (docs/flash-busy.md, g0_fault_stop).
        elf = os.path.join(IMAGES, "km-servo-stm32g031.elf")
        poll = vg031.symbol(elf, "km_app_poll")
        lo, hi = vg031.symbol(elf, "__stack_limit"), vg031.symbol(elf, "__stack_guard_end")
        self.assertEqual(hi - lo, 128, "the guard band this test was written for")
        for word in (0, 13, 31):
            with self.subTest(word=word):
                m = vg031.make(argparse.Namespace(boot=None, app=None, elf=elf, app_elf=None), watch=[poll])
                self.assertTrue(to_main_loop(m, poll))
                m.run_until(m.now + (300 + word) * MS)
                self.assertEqual(m.resets, [], "reset before the band was touched")
                at = lo + 4 * word
                self.assertEqual(bytes(m.uc.mem_read(at, 4)), (0x5AFE57AC).to_bytes(4, "little"), "unpainted")
                m.uc.mem_write(at, (0x12345678).to_bytes(4, "little"))
                written = m.now
                self.assertTrue(m.run_until(m.now + 20 * MS, stop=lambda: bool(m.resets)), "no reset")
                seen_ms = (m.resets[0][0] - written) / MS
                self.assertLessEqual(seen_ms, 9.0, "the band is checked whole every 8 ms")
                self.assertEqual(m.resets[0][1], "sysresetreq")
                hits = len(m.watches[poll])
                self.assertTrue(m.run_until(m.now + 200 * MS, stop=lambda: len(m.watches[poll]) > hits))
                m.run_until(m.now + 2 * MS)
                # the record in .noinit: kind 0x100, pc 0, lr, check = ~(magic ^ kind ^ pc ^ lr)
                ram = bytes(m.uc.mem_read(0x20000000, 8192))
                records = [i for i in range(4, len(ram) - 16, 4)
                           if ram[i:i + 8] == (0x100).to_bytes(8, "little")
                           and int.from_bytes(ram[i + 12:i + 16], "little")
                           == ~(0xFA017EC0 ^ 0x100 ^ int.from_bytes(ram[i + 8:i + 12], "little")) & 0xFFFFFFFF]
                self.assertTrue(records, "no fault record of kind 0x100 in SRAM")
                answer, _ = exchange(m, frame(0, 0x7F, 0x02))
                print("stack guard word %d written: reset %.3f ms later; 0x7F reset cause answer %s"
                      % (word, seen_ms, answer.hex(" ")))
                self.assertEqual(answer[:7], bytes.fromhex("F9F500047F0204"), answer.hex(" "))


def bridge_free(m):
    """PA6 and PA7 low outputs and TIM3's outputs off (boards/stm32g031/fault.c)."""
    moder, odr = m.gpioa.r[0x00], m.gpioa.r[0x14]
    return ((moder >> 12) & 3, (moder >> 14) & 3) == (1, 1) and not odr & 0xC0 and m.tim3.r[0x20] == 0


def main():
    global IMAGES
    IMAGES = sys.argv.pop(1)
    needed = ("km-servo-stm32g031.elf", "km-boot-stm32g031.elf", "km-servo-app-stm32g031.kmfw")
    missing = [n for n in needed if not os.path.exists(os.path.join(IMAGES, n))]
    if missing:
        print("images missing (%s): build the stm32g031 preset first" % ", ".join(missing))
        sys.exit(1)
    unittest.main(verbosity=2)


if __name__ == "__main__":
    main()
