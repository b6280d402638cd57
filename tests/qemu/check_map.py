#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Check a firmware image's linker map for what the bar forbids: a heap
(malloc and friends, _sbrk) or stdio pulled in by accident. Fails, with the
build advice, if the map is missing."""
import re
import sys
from pathlib import Path

FORBIDDEN = ["malloc", "_malloc_r", "free", "_free_r", "calloc", "realloc", "_sbrk", "_sbrk_r",
             "printf", "_printf_r", "puts", "__aeabi_fadd", "__aeabi_dadd"]


def main() -> int:
    if len(sys.argv) < 2:
        print("usage: check_map.py <image.map>...", file=sys.stderr)
        return 2
    bad = 0
    for arg in sys.argv[1:]:
        m = Path(arg)
        if not m.is_file():
            print(f"FAIL: {m} not found: build the qemu preset first "
                  "(cmake --preset qemu && cmake --build --preset qemu)", file=sys.stderr)
            return 1
        text = m.read_text(errors="replace")
        # Symbols defined in the output appear as "0x<addr>  <name>" lines.
        defined = set(re.findall(r"^\s+0x[0-9a-f]+\s+([A-Za-z_][A-Za-z0-9_]*)\s*$", text, re.M))
        found = sorted(s for s in FORBIDDEN if s in defined)
        print(("FAIL " if found else "PASS ") + f"{m.name}: " + (", ".join(found) if found else "no heap, no stdio, no soft float"))
        bad += bool(found)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
