#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Tests of tools/check/size-by-source on a small Cortex-M0+ image built here
with arm-none-eabi-gcc: each source file is charged exactly the bytes of its
own functions (nm's sizes), a function inlined from a header is charged to
the header, and the total is every function's bytes. Skipped when the cross
compiler is missing."""
import importlib.machinery
import importlib.util
import shutil
import subprocess
import tempfile
import unittest
from pathlib import Path

TOOL = Path(__file__).resolve().parents[2] / "tools" / "check" / "size-by-source"
GCC = shutil.which("arm-none-eabi-gcc")

HEADER = r"""
static inline __attribute__((always_inline)) int twice(volatile int *p) { return *p * 2 + *p; }
"""
SRC_A = r"""
#include "h.h"
volatile int sink;
__attribute__((noinline)) int a_one(void) { return twice(&sink) + 1; }
void Reset_Handler(void) { for (;;) { sink = a_one(); } }
"""
SRC_B = r"""
extern volatile int sink;
__attribute__((noinline)) int b_one(int x) { return x * 3 + sink; }
__attribute__((noinline)) int b_two(int x) { return b_one(x) - sink; }
"""
LD = """
MEMORY { FLASH (rx) : ORIGIN = 0x08000000, LENGTH = 16K
         RAM (rwx) : ORIGIN = 0x20000000, LENGTH = 4K }
SECTIONS { .text : { *(.text .text.*) } > FLASH  .bss (NOLOAD) : { *(.bss .bss.*) } > RAM }
ENTRY(Reset_Handler)
"""


def load_tool():
    """tools/check/size-by-source as a module (its name has no .py)."""
    loader = importlib.machinery.SourceFileLoader("size_by_source", str(TOOL))
    spec = importlib.util.spec_from_loader("size_by_source", loader)
    mod = importlib.util.module_from_spec(spec)
    loader.exec_module(mod)
    return mod


@unittest.skipIf(GCC is None, "arm-none-eabi-gcc missing")
class SizeBySource(unittest.TestCase):
    def build(self, d):
        """The image of a.c, b.c and h.h, linked with --gc-sections."""
        for name, text in (("h.h", HEADER), ("a.c", SRC_A), ("b.c", SRC_B), ("img.ld", LD)):
            (d / name).write_text(text)
        elf = d / "img.elf"
        subprocess.run([GCC, "-mcpu=cortex-m0plus", "-mthumb", "-Os", "-g", "-ffunction-sections",
                        "-nostdlib", "-Wl,--gc-sections", "-Wl,--undefined=b_two", "-T", str(d / "img.ld"),
                        str(d / "a.c"), str(d / "b.c"), "-o", str(elf)], check=True, cwd=d)
        return elf

    def nm_sizes(self, elf):
        """Function sizes from nm."""
        out = subprocess.run(["arm-none-eabi-nm", "-S", str(elf)], capture_output=True, text=True,
                             check=True).stdout
        sizes = {}
        for line in out.splitlines():
            parts = line.split()
            if len(parts) == 4 and parts[2] in "tT":
                sizes[parts[3]] = int(parts[1], 16)
        return sizes

    def test_each_file_gets_its_functions_bytes(self):
        tool = load_tool()
        with tempfile.TemporaryDirectory() as tmp:
            elf = self.build(Path(tmp))
            by = tool.bytes_by_source(tool.instructions(str(elf)), tool.symbol_ends(str(elf)))
            sizes = self.nm_sizes(elf)
        self.assertEqual(by["b.c"], sizes["b_one"] + sizes["b_two"])
        self.assertGreater(by["h.h"], 0)  # twice(), inlined into a_one
        self.assertEqual(by["a.c"] + by["h.h"], sizes["a_one"] + sizes["Reset_Handler"])
        self.assertEqual(sum(by.values()), sum(sizes.values()))


if __name__ == "__main__":
    unittest.main()
