#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Tests of tools/gen/reg-hooks, the generator of protocol/'s distinct hook
lists (docs/architecture.md "Register hooks"): each header it writes is
compiled with the host C compiler and its lists printed, for a small .def
with every construct the generator reads (shared hooks, a row over two
lines, comments, #if/#elif/#else/#ifdef/#ifndef) and for
protocol/km_registers.def in both motor-mode builds. A malformed .def
fails (exit 2)."""
import os
import shutil
import subprocess
import tempfile
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
GEN = ROOT / "tools" / "gen" / "reg-hooks"
CC = shutil.which("cc") or shutil.which("gcc")

FIXTURE = """/* KM_REG(0x00, IN_COMMENT, KM_R, 0, KM_L_U8, 0, 0, 0, 0, commented, commented) */
KM_REG(0x01, A, KM_R,  0, KM_L_U8, (1u | (2u << 8)), 0, 0, 0, alpha, none)
KM_REG(0x02, B, KM_RW, 0, KM_L_U8, 0, 0, 0, KM_K(1) | KM_K(2), stored, stored)
KM_REG(0x03, C, KM_RW, 0, KM_L_U8,
       0, 0, 0, 0, alpha, stored) // KM_REG(0x09, X, KM_R, 0, 0, 0, 0, 0, 0, line, line)
#if FEAT
KM_REG(0x04, D, KM_W,  0, KM_L_U8, 0, 0, 0, 0, none, only_on)
#elif FEAT2
KM_REG(0x04, D, KM_W,  0, KM_L_U8, 0, 0, 0, 0, none, only_two)
#else
KM_REG(0x04, D, KM_W,  0, KM_L_U8, 0, 0, 0, 0, none, only_off)
#endif
#ifdef EXTRA
KM_REG(0x05, E, KM_R,  0, KM_L_U8, 0, 0, 0, 0, extra, stored)
#endif
#ifndef EXTRA
KM_REG(0x06, F, KM_R,  0, KM_L_U8, 0, 0, 0, 0, alpha, none)
#endif
"""

PRINT_LISTS = r"""
#include <stdio.h>
#include "km_reg_hooks.h"
#define KM_PRINT(name) printf("%s ", #name);
int main(void)
{
    KM_RD_HOOKS(KM_PRINT)
    printf("| ");
    KM_WR_HOOKS(KM_PRINT)
    printf("| %u %u\n", KM_RD_HOOK_BITS, KM_WR_HOOK_BITS);
    return 0;
}
"""


class RegHooksTest(unittest.TestCase):
    """reg-hooks on a fixture and on the firmware's .def."""

    def setUp(self):
        self.assertIsNotNone(CC, "no host C compiler (cc or gcc) on PATH")
        self.tmp = Path(tempfile.mkdtemp(prefix="reg-hooks-"))
        (self.tmp / "print.c").write_text(PRINT_LISTS)

    def tearDown(self):
        shutil.rmtree(self.tmp)

    def generate(self, def_path):
        """Runs the generator; returns (exit status, stderr)."""
        r = subprocess.run([str(GEN), str(def_path), str(self.tmp / "km_reg_hooks.h")],
                           capture_output=True, text=True, check=False)
        return r.returncode, r.stderr

    def lists(self, *defines):
        """The lists the header gives with these -D options, as printed."""
        exe = self.tmp / "print"
        subprocess.run([CC, "-std=c11", "-Wall", "-Wextra", "-Werror", *defines, "-I", str(self.tmp),
                        str(self.tmp / "print.c"), "-o", str(exe)], check=True)
        return subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.split()

    def fixture(self, text=FIXTURE):
        """Writes a .def and generates its header; asserts success."""
        path = self.tmp / "km_registers.def"
        path.write_text(text)
        self.assertEqual(self.generate(path), (0, ""))
        return path

    def test_each_hook_once_in_first_use_order(self):
        self.fixture()
        self.assertEqual(self.lists("-DFEAT=1", "-DFEAT2=0"),
                         ["alpha", "stored", "none", "|", "none", "stored", "only_on", "|", "2", "3"])

    def test_conditional_hooks_follow_their_rows(self):
        self.fixture()
        self.assertEqual(self.lists("-DFEAT=0", "-DFEAT2=1")[4:8], ["none", "stored", "only_two", "|"])
        self.assertEqual(self.lists("-DFEAT=0", "-DFEAT2=0")[4:8], ["none", "stored", "only_off", "|"])
        self.assertEqual(self.lists("-DFEAT=1", "-DFEAT2=1", "-DEXTRA")[:5],
                         ["alpha", "stored", "none", "extra", "|"])

    def test_comments_are_not_rows(self):
        text = (self.tmp / "km_reg_hooks.h")
        self.fixture()
        body = text.read_text()
        self.assertNotIn("commented", body)
        self.assertNotIn("line", body)

    def test_bits_grow_with_the_hook_count(self):
        for count, bits in ((1, 1), (2, 1), (3, 2), (16, 4), (17, 5)):
            rows = "".join("KM_REG(%d, R%d, KM_R, 0, KM_L_U8, 0, 0, 0, 0, h%d, none)\n" % (i, i, i)
                           for i in range(count))
            self.fixture(rows)
            printed = self.lists()
            self.assertEqual(printed[count], "|")
            self.assertEqual(printed[-2:], [str(bits), "1"], count)

    def test_unchanged_output_is_not_rewritten(self):
        path = self.fixture()
        out = self.tmp / "km_reg_hooks.h"
        os.utime(out, (1, 1))
        self.assertEqual(self.generate(path), (0, ""))
        self.assertEqual(out.stat().st_mtime, 1)
        path.write_text(FIXTURE.replace("only_on", "only_one"))
        self.assertEqual(self.generate(path), (0, ""))
        self.assertNotEqual(out.stat().st_mtime, 1)

    def test_malformed_def_fails(self):
        bad = {
            "ten columns": "KM_REG(0x01, A, KM_R, 0, KM_L_U8, 0, 0, 0, 0, alpha)\n",
            "hook not a name": "KM_REG(0x01, A, KM_R, 0, KM_L_U8, 0, 0, 0, 0, alpha, 1 + 2)\n",
            "unterminated row": "KM_REG(0x01, A, KM_R, 0, KM_L_U8, 0, 0, 0, 0, alpha, none\n",
            "#if without #endif": "#if FEAT\nKM_REG(0x01, A, KM_R, 0, KM_L_U8, 0, 0, 0, 0, alpha, none)\n",
            "#endif without #if": "#endif\n",
            "#else without #if": "#else\n",
        }
        path = self.tmp / "bad.def"
        for name, text in bad.items():
            path.write_text(text)
            status, err = self.generate(path)
            self.assertEqual(status, 2, name)
            self.assertIn("reg-hooks:", err, name)
            self.assertFalse((self.tmp / "km_reg_hooks.h").exists(), name)
        self.assertEqual(self.generate(self.tmp / "missing.def")[0], 2)

    def test_firmware_def_in_both_motor_builds(self):
        self.assertEqual(self.generate(ROOT / "protocol" / "km_registers.def"), (0, ""))
        with_motor = self.lists("-DKM_FEATURE_MOTOR_MODE=1")
        without = self.lists("-DKM_FEATURE_MOTOR_MODE=0")
        self.assertIn("motor_advanced", with_motor)
        self.assertNotIn("motor_advanced", without)
        self.assertEqual([h for h in with_motor if h != "motor_advanced"], without)
        rd, wr = with_motor[:with_motor.index("|")], with_motor[with_motor.index("|") + 1:-3]
        self.assertEqual(len(rd), len(set(rd)))
        self.assertEqual(len(wr), len(set(wr)))
        self.assertIn("stored", rd)
        self.assertIn("none", wr)


if __name__ == "__main__":
    unittest.main()
