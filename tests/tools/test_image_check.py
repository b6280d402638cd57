#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Tests of tools/check/image-check on small Cortex-M0+ images built here with
arm-none-eabi-gcc: each failure the checks exist for (a heap, recursion, an
indirect call nobody described, a stack over its reserve, an interrupt path
that reaches flash) must fail the check, and the clean image must pass with
the stack figure its frames add up to. Skipped when the cross compiler is
missing."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

TOOLS = Path(__file__).resolve().parents[2] / "tools" / "check"
GCC = shutil.which("arm-none-eabi-gcc")

LD = """
MEMORY { FLASH (rx) : ORIGIN = 0x08000000, LENGTH = 16K
         RAM (rwx) : ORIGIN = 0x20000000, LENGTH = 4K }
SECTIONS {
  .isr_vector : { KEEP(*(.isr_vector)) } > FLASH
  .stack (NOLOAD) : { _sstack = .; . = . + STACK; _estack = .; } > RAM
  .ramfunc : { *(.ramfunc .ramfunc.*) } > RAM AT > FLASH
  .text : { *(.text .text.*) *(.rodata .rodata.*) } > FLASH
  .bss (NOLOAD) : { *(.bss .bss.*) } > RAM
}
"""

SRC = r"""
typedef void (*fn_t)(void);
extern unsigned _estack[];
void Reset_Handler(void);
void Irq_Handler(void);
__attribute__((section(".isr_vector"), used))
const fn_t vectors[4] = {(fn_t)_estack, Reset_Handler, 0, Irq_Handler};

volatile int sink;
__attribute__((noinline)) static void leaf(void) { volatile char buf[64]; buf[0] = 1; sink = buf[0]; }
__attribute__((noinline)) void callback(void) { sink = 2; }
fn_t volatile hook = callback;
#ifdef WITH_MALLOC
__attribute__((noinline)) void *malloc(unsigned n) { sink = (int)n; return 0; }
#endif
#ifdef WITH_RECURSION
__attribute__((noinline)) int rec(int n) { return n > 1 ? rec(n - 1) + rec(n - 2) : sink; }
#endif
#ifdef IRQ_IN_RAM
__attribute__((section(".ramfunc.irq"), noinline))
#endif
void Irq_Handler(void)
{
#ifdef WITH_FLASH_CALL
    leaf();
#endif
    sink = 3;
}
#ifdef WITH_DISPATCH
static void dispatch(fn_t f) { f(); }
#endif
void Reset_Handler(void)
{
    leaf();
#ifdef WITH_DISPATCH
    dispatch(hook);
#else
    hook();
#endif
#ifdef WITH_MALLOC
    sink = malloc(4) != 0;
#endif
#ifdef WITH_RECURSION
    sink = rec(sink);
#endif
    for (;;) {
    }
}
"""


@unittest.skipIf(GCC is None, "arm-none-eabi-gcc not installed")
class ImageCheckTest(unittest.TestCase):
    def setUp(self):
        self.dir = Path(tempfile.mkdtemp(prefix="image-check-"))

    def tearDown(self):
        shutil.rmtree(self.dir)

    def build(self, *defines, stack=1024, lto=False, origin="0x08000000"):
        (self.dir / "t.c").write_text(SRC)
        (self.dir / "t.ld").write_text(f"STACK = {stack};\n" + LD.replace("0x08000000", origin))
        obj = self.dir / "t.o"
        elf = self.dir / "t.elf"
        flags = ["-mcpu=cortex-m0plus", "-mthumb", "-Os", "-ffunction-sections", "-fstack-usage"]
        if lto:
            flags += ["-flto", "-g"]
        subprocess.run([GCC, *flags, *[f"-D{d}" for d in defines], "-c", str(self.dir / "t.c"),
                        "-o", str(obj)], check=True, cwd=self.dir)
        subprocess.run([GCC, *flags, "-nostdlib", "-T", str(self.dir / "t.ld"), str(obj), "-o", str(elf),
                        f"-Wl,-Map={self.dir / 't.map'}", "-Wl,--emit-relocs"], check=True, cwd=self.dir)
        return elf

    def check(self, elf, cfg, *args):
        path = self.dir / "cfg.json"
        path.write_text(json.dumps(cfg))
        r = subprocess.run([sys.executable, str(TOOLS / "image-check"), str(elf), "--config", str(path),
                            "--su-root", str(self.dir), *args], capture_output=True, text=True)
        return r.returncode, r.stdout + r.stderr

    def config(self, describe=True, ram=False):
        cfg = {"vectors": {"symbol": "vectors", "count": 4},
               "irq": {"Irq_Handler": 0},
               "stack": {"top": "_estack", "limit": "_sstack"},
               "indirect": {"Reset_Handler": ["callback"]} if describe else {}}
        if ram:
            cfg["ram"] = {"flash_range": ["0x08000000", "0x08004000"], "roots": ["Irq_Handler"]}
        return cfg

    def test_clean_image_passes_with_its_frames_added_up(self):
        rc, out = self.check(self.build(), self.config())
        self.assertEqual(rc, 0, out)
        self.assertIn("PASS heap", out)
        self.assertIn("PASS stack", out)
        self.assertNotIn("no .su", out)  # every frame came from t.su
        # leaf's 64-byte buffer is the deepest frame under Reset_Handler.
        self.assertRegex(out, r"main \(from Reset_Handler\) \d+ B via Reset_Handler > leaf")

    def test_budget_takes_the_application_header_from_its_link_address(self):
        """An application linked 32 or 256 B into its region's page is
        charged that header (docs/update.md §2: the 32 KiB build's 32-byte
        header), on top of its .bin."""
        budget = {"flash": 32768, "boot_max": 4096, "store": 6144, "page": 2048, "ram_max": 6144,
                  "role": "app"}
        for origin, header in (("0x08001020", 32), ("0x08002100", 256)):
            elf = self.build(origin=origin)
            rc, out = self.check(elf, {"budget": budget}, "--checks", "budget", "--enforce-budget")
            size = elf.with_suffix(".bin").stat().st_size
            self.assertEqual(rc, 0, out)
            self.assertIn(f"application {size:,} + {header} B header = {size + header:,} B", out)
            elf.with_suffix(".bin").unlink()

    def test_vector_count_defaults_to_the_table_symbol_size(self):
        """Without "count" the table is as long as its symbol (the 32 KiB
        STM32G031 build's 8-word flash table, startup.c): its handlers are
        still found, each at its interrupt's priority."""
        cfg = self.config()
        del cfg["vectors"]["count"]
        rc, out = self.check(self.build(), cfg)
        self.assertEqual(rc, 0, out)
        self.assertIn("PASS stack", out)
        self.assertRegex(out, r"priority +0: Irq_Handler")

    def test_heap_fails(self):
        rc, out = self.check(self.build("WITH_MALLOC"), self.config())
        self.assertEqual(rc, 1, out)
        self.assertIn("FAIL heap: malloc", out)

    def test_recursion_fails(self):
        rc, out = self.check(self.build("WITH_RECURSION"), self.config())
        self.assertEqual(rc, 1, out)
        self.assertIn("FAIL stack: recursion: rec", out)

    def test_undescribed_indirect_call_fails(self):
        rc, out = self.check(self.build(), self.config(describe=False))
        self.assertEqual(rc, 1, out)
        self.assertIn("indirect call in Reset_Handler", out)
        self.assertIn("callback [t.o]: address taken", out)

    def test_indirect_call_described_by_patterns(self):
        # A shell pattern names a table's callbacks (km_rd_*) and a caller
        # (its object given); one that names nothing leaves the callback
        # unclaimed, and that fails as a missing description does.
        cfg = self.config(describe=False)
        cfg["indirect"] = {"Reset_*@t.o": ["call*"]}
        rc, out = self.check(self.build(), cfg)
        self.assertEqual(rc, 0, out)
        cfg["indirect"] = {"Reset_Handler": ["cb_*"]}
        rc, out = self.check(self.build(), cfg)
        self.assertEqual(rc, 1, out)
        self.assertIn("callback [t.o]: address taken", out)

    def test_stack_over_reserve_fails(self):
        rc, out = self.check(self.build(stack=64), self.config())
        self.assertEqual(rc, 1, out)
        self.assertIn("exceeds the 64 B the linker script reserves", out)

    def test_ram_path_reaching_flash_fails(self):
        rc, out = self.check(self.build("IRQ_IN_RAM", "WITH_FLASH_CALL"), self.config(ram=True))
        self.assertEqual(rc, 1, out)
        self.assertRegex(out, r"FAIL ram: leaf \[t.o\] at 0x080\w+ is in flash, reached: leaf <- .*Irq_Handler")

    def test_ram_path_all_in_ram_passes(self):
        rc, out = self.check(self.build("IRQ_IN_RAM"), self.config(ram=True))
        self.assertEqual(rc, 0, out)
        self.assertIn("PASS ram", out)

    # docs/footprint.md "LTO": the functions come from a link-time partition;
    # an indirect call inlined into another function is judged by the config
    # entry of the function it was written in (the debug line table's
    # inline chain), and fails when that function has none.
    def lto_config(self, describe):
        cfg = self.config(describe=False)
        cfg["indirect"] = {"dispatch@t.c.obj": ["callback"]} if describe else {}
        return cfg

    def test_lto_inlined_call_site_uses_its_origins_entry(self):
        rc, out = self.check(self.build("WITH_DISPATCH", lto=True), self.lto_config(True))
        self.assertEqual(rc, 0, out)
        self.assertRegex(out, r"indirect call in Reset_Handler \[t.c, LTO\] at 0x\w+: inlined from dispatch \(t.c\)")

    def test_lto_inlined_call_site_without_entry_fails(self):
        rc, out = self.check(self.build("WITH_DISPATCH", lto=True), self.lto_config(False))
        self.assertEqual(rc, 1, out)
        self.assertIn("(written in dispatch, t.c) not described in the config", out)


if __name__ == "__main__":
    unittest.main()
