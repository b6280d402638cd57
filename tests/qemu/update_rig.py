# SPDX-License-Identifier: Apache-2.0
"""What the QEMU update tests share (update_e2e.py, update_trial.py): the
qemu-microbit build's update images, servos that boot through the
bootloader on a sim/bus/servo-bus with a QEMU monitor each, the
tools/servo-update command line for them, and the closing report."""
import os
import tempfile

import simbus  # noqa: E402  (sim/bus on PYTHONPATH)

REPO = simbus.REPO
BOOT = "km-servo-boot-qemu-microbit.elf"  # the bootloader with v1 in its factory slot


def add_build_arg(ap):
    """--build-qemu DIR: the qemu-microbit build tree (default: servo-bus's, sim/bus/simbus.py)."""
    ap.add_argument("--build-qemu", help="the qemu-microbit build tree (default: $KM_BUILD_DIR_qemu_microbit, "
                    "else the qemu preset's)")


def images(build_qemu, names):
    """{name: path} of these images of the qemu-microbit build; None after
    printing each one missing and the commands that build it."""
    tree = simbus.build_dir("qemu", build_qemu)
    paths = {n: os.path.join(tree, "boards", "qemu-microbit", n) for n in names}
    missing = [p for p in paths.values() if not os.path.isfile(p)]
    for p in missing:
        print("missing %s: %s" % (p, simbus.build_hint("qemu", tree)))
    return None if missing else paths


class BootBus:
    """Servos that boot through the bootloader on a servo-bus, each with its
    QEMU monitor on a socket in a temporary folder."""

    def __init__(self, ids, boot):
        self.ids = ids
        self.monitors = tempfile.TemporaryDirectory(prefix="update-qemu-")
        try:
            self.bus = simbus.ServoBusProcess(["--ids", ",".join(map(str, ids)), "--image", boot,
                                               "--monitor-dir", self.monitors.name])
        except BaseException:
            self.monitors.cleanup()
            raise
        self.spec = self.bus.spec
        print("bus:", self.spec, flush=True)

    def update_argv(self):
        """tools/servo-update for every servo of this bus; image and options follow."""
        return [os.path.join(REPO, "tools", "servo-update"), "--bus", self.spec,
                "--ids", ",".join(map(str, self.ids))]

    def monitor_path(self, dev_id):
        """The Unix socket of one servo's QEMU monitor (servo-bus --monitor-dir)."""
        return os.path.join(self.monitors.name, "servo-%d.sock" % dev_id)

    def close(self):
        self.bus.close()
        self.monitors.cleanup()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def report(failures):
    """Prints each failure, or "all checks passed" when there is none; the exit status."""
    for f in failures:
        print("FAIL", f)
    if failures:
        return 1
    print("all checks passed")
    return 0
