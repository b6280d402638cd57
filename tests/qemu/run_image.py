#!/usr/bin/env python3
"""Run one test image in QEMU's microbit machine with semihosting and exit
with the guest's exit code (SYS_EXIT_EXTENDED). A missing image is a
failure that says how to build it, never a silent skip."""
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
           "-kernel", str(image)]
    print(" ".join(cmd), flush=True)
    try:
        return subprocess.run(cmd, timeout=timeout).returncode
    except subprocess.TimeoutExpired:
        print(f"FAIL: {image.name} did not exit within {timeout} s", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
