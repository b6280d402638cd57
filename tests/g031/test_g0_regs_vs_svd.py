#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""boards/stm32g031/g0_regs.h against ST's description of the STM32G031
(sim/g031/g031_regmap.py, generated from the CMSIS SVD): every base
address, register offset, bit, shift, mask and field value the header
defines must agree with it. A define the test cannot place (no peripheral,
register or field of that name) fails too, unless it is listed in
NOT_IN_SVD with where RM0444 gives it; a disagreement fails unless it is
listed in RECORDED_DIFFERENCES with why it is harmless.

    test_g0_regs_vs_svd.py [path/to/g0_regs.h]
"""
import os
import re
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
import g031_regmap as R  # noqa: E402

HEADER = os.path.join(HERE, "..", "..", "boards", "stm32g031", "g0_regs.h")

# Header prefix -> the SVD peripherals it addresses (TIM_ and GPIO_ macros
# take the base as a parameter).
PREFIXES = {"FLASH": ["FLASH"], "RCC": ["RCC"], "USART1": ["USART1"], "USART": ["USART1"],
            "TIM": ["TIM2", "TIM3"], "ADC": ["ADC"], "DMA1": ["DMA1"], "DMA": ["DMA1"],
            "DMAMUX": ["DMAMUX"], "IWDG": ["IWDG"], "GPIO": ["GPIOA", "GPIOB"]}
# Header register name -> SVD register name where ST spells it otherwise.
REG_ALIASES = {("RCC", "PLLCFGR"): "PLLSYSCFGR", ("ADC", "CFGR1"): "ADC_CFGR1",
               ("ADC", "CFGR2"): "ADC_CFGR2", ("DMA1", "CCR1"): "DMA_CCR1",
               ("DMA1", "CNDTR1"): "DMA_CNDTR1", ("DMA1", "CPAR1"): "DMA_CPAR1",
               ("DMA1", "CMAR1"): "DMA_CMAR1", ("DMA1", "CCR"): "DMA_CCR1",
               ("TIM2", "CCMR1"): "CCMR1_Output", ("TIM3", "CCMR1"): "CCMR1_Output",
               ("GPIOA", "AFR"): "AFRL", ("GPIOB", "AFR"): "AFRL"}
# (SVD register, header field) -> SVD field where the names differ.
FIELD_ALIASES = {("SR", "BSY1"): "BSY", ("SR", "MISSERR"): "MISERR",
                 ("PLLSYSCFGR", "SRC"): "PLLSRC", ("PLLSYSCFGR", "M"): "PLLM",
                 ("PLLSYSCFGR", "N"): "PLLN", ("PLLSYSCFGR", "REN"): "PLLREN",
                 ("PLLSYSCFGR", "R"): "PLLR", ("IOPENR", "GPIOA"): "IOPAEN",
                 ("IOPENR", "GPIOB"): "IOPBEN", ("AHBENR", "DMA1"): "DMAEN",
                 ("APBENR1", "TIM2"): "TIM2EN", ("APBENR1", "TIM3"): "TIM3EN",
                 ("APBENR2", "USART1"): "USART1EN", ("APBENR2", "ADC"): "ADCEN",
                 ("ISR", "NE"): "NF", ("ICR", "NECF"): "NCF"}
# Field values whose name is not register_field: name -> (peripheral, register, field).
VALUES = {"FLASH_KEY1": ("FLASH", "KEYR", "KEYR"), "FLASH_KEY2": ("FLASH", "KEYR", "KEYR"),
          "IWDG_KEY_UNLOCK": ("IWDG", "KR", "KEY"), "IWDG_KEY_START": ("IWDG", "KR", "KEY"),
          "IWDG_KEY_KICK": ("IWDG", "KR", "KEY")}
# Defines the SVD does not describe, and where RM0444 gives them.
NOT_IN_SVD = {
    "G0_REGS_H": "include guard",
    "FLASH_MAIN_BASE": "§2.2.2 memory map: main flash at 0x0800 0000",
    "FLASH_PAGE_SIZE": "§3.3.1: 2 KiB pages",
    "UID_BASE_R": "§40.1 unique device ID (engineering bytes, not a peripheral)",
    "DMAMUX_REQ_ADC": "§11.3.2 table 59, DMAMUX request 5 = ADC",
    "FLASH_SR_ERRORS": "OR of SR bits checked one by one above",
    "RCC_CSR_RESET_FLAGS": "OR of CSR bits checked one by one above",
}
# Known disagreements, each harmless for the reason given.
RECORDED_DIFFERENCES = {}


def _read(path):
    with open(path) as f:
        return f.read()


def read_defines(path):
    """{name: (params or None, expression)} of the header's #defines."""
    text = re.sub(r"/\*.*?\*/", " ", _read(path), flags=re.S).replace("\\\n", " ")
    out = {}
    for m in re.finditer(r"^#define\s+(\w+)(\(([^)]*)\))?[ \t]*(.*)$", text, flags=re.M):
        params = [p.strip() for p in m.group(3).split(",")] if m.group(2) else None
        out[m.group(1)] = (params, m.group(4).strip())
    return out


def evaluate(defines, name, args=None):
    """Value of a define (G0_REG(x) read as x, G0_REG_AT(b, o) as b + o; parameters given by args)."""
    params, expr = defines[name]
    expr = re.sub(r"\b(0x[0-9A-Fa-f]+|\d+)[uU]\b", r"\1", expr)
    expr = re.sub(r"\bG0_REG_AT\(", "_g0_at(", expr).replace("G0_REG", "")
    expr = expr.replace("(uint32_t)", "")
    for p, v in zip(params or [], args or []):
        expr = re.sub(r"\b%s\b" % p, str(v), expr)

    def sub(m):
        return str(evaluate(defines, m.group(0))) if m.group(0) in defines else m.group(0)
    expr = re.sub(r"\b[A-Za-z_]\w*\b", sub, expr)
    return eval(expr, {"__builtins__": {}, "_g0_at": lambda base, offset: base + offset})  # noqa: S307 - the project's own header


def field_mask(field):
    lsb, width = field
    return ((1 << width) - 1) << lsb


class Checker:
    """Places each define in the SVD and compares; collects the findings."""

    def __init__(self, defines):
        self.d = defines
        self.regs = {}        # (prefix, header register) -> [(peripheral, SVD register)]
        self.findings = []    # (name, what is wrong)
        self.checked = set()

    def bases(self):
        for name in [n for n in self.d if n.endswith("_BASE_R") and n != "UID_BASE_R"]:
            value = evaluate(self.d, name)
            hits = [p for p, (base, _) in R.PERIPHERALS.items() if base == value]
            self._done(name, bool(hits), "0x%08X is no peripheral's base" % value)

    def registers(self):
        """Register macros: G0_REG(base + offset)."""
        for name, (params, expr) in self.d.items():
            if "G0_REG" not in expr:
                continue
            prefix, reg = self._split_prefix(name)
            if prefix is None:
                continue
            for periph in PREFIXES[prefix]:
                base, regs = R.PERIPHERALS[periph]
                addr = evaluate(self.d, name, [base, 0] if params else None)
                svd = REG_ALIASES.get((periph, reg), reg)
                ok = svd in regs and regs[svd][0] == addr - base
                self._done(name, ok, "%s: %s at offset 0x%X, SVD %s" % (
                    periph, svd, addr - base, hex(regs[svd][0]) if svd in regs else "has no such register"))
                self.regs.setdefault((prefix, reg), []).append((periph, svd))
            if name == "GPIO_AFR":   # n = 1: the high register
                ok = all(evaluate(self.d, name, [R.PERIPHERALS[p][0], 1]) - R.PERIPHERALS[p][0]
                         == R.PERIPHERALS[p][1]["AFRH"][0] for p in PREFIXES["GPIO"])
                self._done(name, ok, "AFR(p, 1) is not AFRH")

    def bits(self):
        """Bit, shift, mask and value macros: PREFIX_REG_FIELD[_SHIFT|_MASK|_VALUE]."""
        for name, (params, expr) in self.d.items():
            if name in self.checked or name in NOT_IN_SVD or params is not None:
                continue
            if name in VALUES:
                periph, reg, field = VALUES[name]
                self._value(name, evaluate(self.d, name), R.PERIPHERALS[periph][1][reg][3][field])
                continue
            placed = self._place(name)
            if placed is None:
                self.findings.append((name, "not placed in the SVD (list it in NOT_IN_SVD with its RM0444 section?)"))
                continue
            periph, reg, fname, field, rest = placed
            value = evaluate(self.d, name)
            if rest == "SHIFT":
                self._done(name, value == field[0], "shift %d, SVD %s at bit %d" % (value, fname, field[0]))
            elif rest == "MASK":
                ok = value in (field_mask(field), (1 << field[1]) - 1)
                self._done(name, ok, "mask 0x%X, SVD %s[%d:%d] = 0x%X" % (
                    value, fname, field[0] + field[1] - 1, field[0], field_mask(field)))
            elif rest == "":
                self._done(name, value == field_mask(field), "0x%X, SVD %s = 0x%X" % (value, fname, field_mask(field)))
            else:
                self._value(name, value, field)

    def _value(self, name, value, field):
        """A field value: nonzero and inside the field (shifted or not, for a field at bit 0 both)."""
        ok = value != 0 and (value & ~field_mask(field)) == 0
        self._done(name, ok, "value 0x%X outside the field's bits 0x%X" % (value, field_mask(field)))

    def _split_prefix(self, name):
        for prefix in sorted(PREFIXES, key=len, reverse=True):
            if name.startswith(prefix + "_"):
                return prefix, name[len(prefix) + 1:]
        return None, None

    def _place(self, name):
        """(peripheral, SVD register, SVD field, field, suffix) or None."""
        prefix, rest = self._split_prefix(name)
        if prefix is None:
            return None
        for periph in PREFIXES[prefix]:
            regs = R.PERIPHERALS[periph][1]
            words = rest.split("_")
            for i in range(1, len(words)):
                reg = REG_ALIASES.get((periph, "_".join(words[:i])), "_".join(words[:i]))
                if reg not in regs:
                    continue
                for j in range(len(words), i, -1):
                    hname = "_".join(words[i:j])
                    fname = FIELD_ALIASES.get((reg, hname), hname)
                    if fname in regs[reg][3]:
                        return periph, reg, fname, regs[reg][3][fname], "_".join(words[j:])
        return None

    def _done(self, name, ok, why):
        self.checked.add(name)
        if not ok:
            self.findings.append((name, why))


class HeaderAgainstSvd(unittest.TestCase):
    def test_every_define_agrees_with_the_svd(self):
        defines = read_defines(HEADER)
        c = Checker(defines)
        c.bases()
        c.registers()
        c.bits()
        unexpected = [(n, w) for n, w in c.findings if n not in RECORDED_DIFFERENCES]
        for name, why in sorted(RECORDED_DIFFERENCES.items()):
            print("recorded difference: %s: %s" % (name, why))
        stale = [n for n in RECORDED_DIFFERENCES if n not in dict(c.findings)]
        print("%d defines checked against the SVD, %d not in it (RM0444), %d recorded differences" % (
            len(c.checked), len([n for n in NOT_IN_SVD if n in defines]), len(RECORDED_DIFFERENCES)))
        self.assertEqual(unexpected, [], "g0_regs.h disagrees with the SVD")
        self.assertEqual(stale, [], "recorded differences that agree now: drop them")
        self.assertGreater(len(c.checked), 100)

    def test_checker_catches_a_wrong_bit(self):
        """The comparison can fail: one bit moved is found."""
        defines = read_defines(HEADER)
        defines["USART_ISR_TXE"] = (None, "(1u << 6)")
        c = Checker(defines)
        c.bits()
        self.assertIn("USART_ISR_TXE", dict(c.findings))


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1].endswith(".h"):
        HEADER = sys.argv.pop(1)
    unittest.main(verbosity=2)
