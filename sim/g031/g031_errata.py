# SPDX-License-Identifier: Apache-2.0
"""Where ST's STM32G031 SVD (g031_regmap.py, generated) is wrong for an
emulator, corrected from RM0444 / the Cortex-M0+ TRM. One visible table:
each entry says what the SVD says, what the part does and where that is
written. The emulator applies these over the generated map."""

# (peripheral, register): (svd reset value, corrected reset value, source)
RESET_VALUE = {
    ("RCC", "CR"): (0x00000063, 0x00000500,
                    "RM0444 §5.4.1 RCC_CR reset value 0x0000 0500: HSION and HSIRDY set "
                    "(the SVD's 0x63 has HSIRDY clear, and a clock set-up polling HSIRDY "
                    "would wait for ever)"),
    ("ADC", "CHSELR"): (0x0FFF0000, 0x00000000,
                        "RM0444 §15.12.9 ADC_CHSELR reset value 0x0000 0000"),
}

# CPU facts the SVD's <cpu> block gets wrong.
CPU = {
    "nvicPrioBits": (4, 2, "Cortex-M0+ TRM / ARMv6-M B3.4: 2 priority bits (bits 7:6) per field"),
}


def reset_value(regmap, periph, reg):
    """The reset value of periph.reg: the errata's if listed, else the SVD's."""
    if (periph, reg) in RESET_VALUE:
        return RESET_VALUE[(periph, reg)][1]
    return regmap.PERIPHERALS[periph][1][reg][2]
