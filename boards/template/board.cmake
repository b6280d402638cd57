# SPDX-License-Identifier: Apache-2.0
# The board's declaration (cmake/km_boards.cmake), read before project():
# its name is its folder's. This template is a Cortex-M0 built with
# Debian's arm-none-eabi-gcc and newlib-nano: set -mcpu to your core
# (cortex-m0plus, cortex-m3, cortex-m4...). Every object gets one section
# per function/object (--gc-sections drops what is unused) and
# -fstack-usage (.su files: tools/check/image-check bounds the stack from them).
# No crt0 (startup.c is ours) and no nosys.specs: anything reaching for
# syscalls or a heap fails to link.
set(KM_BOARD_DESCRIPTION "A board made from boards/template (every hal contract empty)")
set(KM_BOARD_TOOLCHAIN arm-none-eabi)
set(KM_BOARD_BUILD_TYPE MinSizeRel)
set(KM_BOARD_COMPILE_OPTIONS -mcpu=cortex-m0 -mthumb -ffunction-sections -fdata-sections
    -fstack-usage)
set(KM_BOARD_LINK_OPTIONS -mcpu=cortex-m0 -mthumb --specs=nano.specs -nostartfiles
    -Wl,--gc-sections)
# Board code that runs without the MCU (conversions, baud dividers...): list
# it here and test it in tests/board/test_<board>_*.c (tests/boards.cmake).
set(KM_BOARD_HOST_SOURCES)
