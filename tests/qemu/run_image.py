#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Run one test image in QEMU's microbit machine with semihosting and exit
with the guest's exit code (SYS_EXIT_EXTENDED). A missing image is a
failure that says how to build it, never a silent skip.

-icount makes virtual time count instructions (64 ns each, about a 16 MHz
M0), so the image's timer checks do not depend on host load: without it,
a busy CI machine stalls the vCPU while QEMU's clock runs on, and a 2 ms
one-shot may fire before the very next instruction checks it has not."""
import subprocess
import sys
from pathlib import Path


def main() -> int:
    if len(sys.argv) != 3:
        print("usage: run_image.py <image.elf> <timeout_s>", file=sys.stderr)
        return 2
    image, timeout = Path(sys.argv[1]), float(sys.argv[2])
    if not image.is_file():
        print(f"FAIL: {image} not found: build the qemu preset first "
              "(cmake --preset qemu && cmake --build --preset qemu)", file=sys.stderr)
        return 1
    cmd = ["qemu-system-arm", "-M", "microbit", "-display", "none", "-monitor", "none",
           "-serial", "null", "-semihosting-config", "enable=on,target=native",
           "-icount", "shift=6,align=off,sleep=off",
           "-kernel", str(image)]
    print(" ".join(cmd), flush=True)
    try:
        return subprocess.run(cmd, timeout=timeout).returncode
    except subprocess.TimeoutExpired:
        print(f"FAIL: {image.name} did not exit within {timeout} s", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
