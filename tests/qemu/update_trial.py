#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""A bad image does not brick a servo (docs/update.md §3a, issue 18 item 1),
on QEMU: two emulated servos (IDs 1 and 2) that boot through the bootloader
(km-servo-boot-qemu-microbit.elf, v1 in its factory slot) on one
sim/bus/servo-bus, each with its QEMU monitor (to read the words the
bootloader and the application share at the top of RAM). For the hang image
(reset vector at `b .`) and then the crash image (reset vector at
`udf #0`), both built by CMake from tests/qemu/trial/bad_image.c and
tools/gen/make-image:
  1. tools/servo-update sends it to both servos (it passes every check, so
     COMMIT and START go through);
  2. both servos must be back in update mode (STATUS state 1, idle) on their
     stored IDs within BOUND_S seconds of the end of that pass, with the
     bad image stored (0x0C software 0x0BAD) and KM_BOOT_TRIAL_MAX = 3
     starts counted;
  3. a broadcast restart keeps them in update mode (the count is kept);
  4. a broadcast 0x78 START gives the image new tries: timed from that
     frame, both are back in update mode again (the worst case, printed);
  5. tools/servo-update sends a good image (v2 after the hang image, v1
     after the crash image) to both at once, broadcast, paced at 19200 baud
     (--baud: on a loaded two-core host two emulators fall seconds behind
     a 115200 block stream and a STATUS goes unanswered; the tool's own
     retry of a pass is allowed and the passes are printed): both answer as
     applications (STATUS state 0) with its version, and still do after the
     2 s trial timer, with their start confirmed in RAM.
Before all that, the good factory image must confirm its start and outlive
the trial timer. Prints "all checks passed" at the end; exit 1 on any
failure.
    update_trial.py [--build-qemu DIR]
"""
import argparse
import re
import struct
import subprocess
import sys
import time

from kmx.bus import Bus  # noqa: E402
from kmx import frame as fr  # noqa: E402
from kmx import update as kmx_update  # noqa: E402
import update_rig as rig  # noqa: E402

IDS = (1, 2)
BOUND_S = 30.0          # stated bound: back in update mode within this (measured: docs/update.md §11)
TRIAL_S = 2.0           # the nRF51 trial timer (boards/qemu-microbit/boot/boot_layout.h)
TRIAL_MAX = 3           # KM_BOOT_TRIAL_MAX
SHARED = 0x20003FE0     # km_boot_shared_t (boot_layout.h BOOT_SHARED_ADDR)
CONFIRMED = 0x4F4B4159  # KM_BOOT_CONFIRMED_MAGIC
TRIAL_KEY = 0x7A1AC0DE  # KM_BOOT_TRIAL_KEY
BAD_SW = 0x0BAD         # the bad images' software version (boards/qemu-microbit/CMakeLists.txt)
GOOD_BAUD = 19200       # servo-update's pacing of the good image: emulators on a loaded host keep up


class Monitor(kmx_update.Monitor):
    """One servo's QEMU human monitor (sim/bus/servo-bus --monitor-dir),
    the client `kmx update --resets` uses, which also reads RAM."""

    def shared(self):
        """The 8 shared words: request, app_running, boot_version, check,
        attempts, attempts_check, confirmed, spare."""
        self.sock.sendall(b"xp /8wx 0x%08x\n" % SHARED)
        out = self._prompt()
        words = [int(w, 16) for w in re.findall(r"0x([0-9a-fA-F]{8})\b", out.split(":", 1)[-1])]
        return words[-8:]


def attempts(words):
    n, check = words[4], words[5]
    return n if check == n ^ TRIAL_KEY else None


def status(bus, dev_id, timeout=0.3):
    """STATUS state (0 application, 1 idle in the bootloader, ...) or None."""
    for f in bus.transact(fr.encode_command(dev_id, 0x78, 0x04, b"\x00\x00"), 1, timeout):
        if f.id == dev_id and not f.is_status and f.cmd == 0x78 and f.addr == 0x04 and f.params:
            return f.params[0]
    return None


def version(bus, dev_id):
    for _ in range(5):
        for f in bus.transact(fr.read(dev_id, 0x0C), 1, 0.3):
            if f.id == dev_id and not f.is_status and f.addr == 0x0C and len(f.params) == 4:
                return struct.unpack("<I", f.params)[0]
    return None


def wait_state(spec, want, since, bound):
    """Seconds from `since` until every servo answers STATUS with `want`,
    {ID: seconds}; None for a servo that did not within `bound`."""
    got = {}
    with Bus(spec, timeout=0.3) as bus:
        while len(got) < len(IDS) and time.monotonic() - since < bound:
            for i in IDS:
                if i not in got and status(bus, i, 0.1) == want:
                    got[i] = time.monotonic() - since
            time.sleep(0.05)
    return {i: got.get(i) for i in IDS}


def main():
    ap = argparse.ArgumentParser()
    rig.add_build_arg(ap)
    a = ap.parse_args()
    good_names = {"v1": ("km-servo-app-qemu-microbit.kmfw", 0x10100100),
                  "v2": ("km-servo-app-v2-qemu-microbit.kmfw", 0x10100102)}
    bad_names = [("hang", "km-bad-hang-qemu-microbit.kmfw", "v2"), ("crash", "km-bad-crash-qemu-microbit.kmfw", "v1")]
    img = rig.images(a.build_qemu, [rig.BOOT] + [g[0] for g in good_names.values()] + [b[1] for b in bad_names])
    if img is None:
        return 1
    good = {k: (img[n], v) for k, (n, v) in good_names.items()}
    bad = [(name, img[n], then) for name, n, then in bad_names]
    failures = []
    with rig.BootBus(IDS, img[rig.BOOT]) as boot_bus:
        spec = boot_bus.spec
        mons = {i: Monitor(boot_bus.monitor_path(i)) for i in IDS}
        update = boot_bus.update_argv()

        def passes(out):
            return 1 + out.count(" interrupted: ")

        def running(image_version, what):
            """Both answer as applications with that version, outlive the
            trial timer, and confirmed their start."""
            time.sleep(TRIAL_S + 1.0)
            with Bus(spec, timeout=0.3) as bus:
                for i in IDS:
                    st, v, words = status(bus, i), version(bus, i), mons[i].shared()
                    print("  ID %d: state %s, 0x0C %s, attempts %s, confirmed %s" % (
                        i, st, "0x%08X" % v if v is not None else None, attempts(words),
                        words[6] == CONFIRMED), flush=True)
                    if st != 0 or v != image_version or words[6] != CONFIRMED or attempts(words) != 1:
                        failures.append("%s: ID %d not running 0x%08X, confirmed, %.0f s after its start"
                                        % (what, i, image_version, TRIAL_S + 1.0))

        print("0: the factory image (v1) confirms its start and outlives the trial timer", flush=True)
        running(good["v1"][1], "0")

        for name, path, then in bad:
            print("%s image: sent with tools/servo-update" % name, flush=True)
            r = subprocess.run(update + [path], capture_output=True, text=True)
            ended = time.monotonic()
            print("  " + r.stdout.strip().replace("\n", "\n  "), flush=True)
            print("  passes: %d" % passes(r.stdout), flush=True)
            back = wait_state(spec, 1, ended, BOUND_S)
            print("  back in update mode, seconds after the pass ended: %s" % back, flush=True)
            if any(t is None for t in back.values()):
                failures.append("%s: not back in update mode within %.0f s: %s" % (name, BOUND_S, back))
                continue
            with Bus(spec, timeout=0.3) as bus:
                for i in IDS:
                    v, words = version(bus, i), mons[i].shared()
                    if v is None or v & 0xFFFF != BAD_SW or attempts(words) != TRIAL_MAX:
                        failures.append("%s: ID %d: 0x0C %s, attempts %s (want the bad image, %d)"
                                        % (name, i, v, attempts(words), TRIAL_MAX))
                bus.send_bytes(fr.restart(0xFE))
            time.sleep(TRIAL_S + 1.0)
            with Bus(spec, timeout=0.3) as bus:
                for i in IDS:
                    if status(bus, i) != 1 or attempts(mons[i].shared()) != TRIAL_MAX:
                        failures.append("%s: ID %d left update mode after a restart" % (name, i))
                t0 = time.monotonic()
                bus.send_bytes(fr.encode_command(0xFE, 0x78, 0x07, bytes([0xE1, 0xE2, 0xE3, 0xE4])))
            time.sleep(0.3)  # START taken: until then they answer from update mode still
            again = wait_state(spec, 1, t0, BOUND_S)
            counted = {i: attempts(mons[i].shared()) for i in IDS}
            print("  START (new tries): back in update mode after %s s, starts counted %s" % (
                {i: None if t is None else round(t, 2) for i, t in again.items()}, counted), flush=True)
            if any(t is None for t in again.values()) or any(c != TRIAL_MAX for c in counted.values()):
                failures.append("%s: after START not back in update mode with %d starts: %s %s"
                                % (name, TRIAL_MAX, again, counted))
            print("%s image: then %s by tools/servo-update" % (name, then), flush=True)
            r = subprocess.run(update + ["--baud", str(GOOD_BAUD), good[then][0]], capture_output=True, text=True)
            print("  " + r.stdout.strip().replace("\n", "\n  "), flush=True)
            print("  passes: %d" % passes(r.stdout), flush=True)
            if r.returncode != 0:
                failures.append("%s: %s did not go through" % (name, then))
            running(good[then][1], name + " then " + then)
    return rig.report(failures)


if __name__ == "__main__":
    sys.exit(main())
