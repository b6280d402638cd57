# SPDX-License-Identifier: Apache-2.0
# The qemu-microbit board's declaration (cmake/km_boards.cmake): QEMU's
# nRF51822 micro:bit, a Cortex-M0, built with Debian's arm-none-eabi-gcc.
# -fstack-usage: a .su file per object, to bound the 2 KiB stack by reading.
# newlib-nano for memcpy/memset only; our own startup (no crt0) and no
# nosys.specs, so anything reaching for syscalls or a heap fails to link.
# The bus floors (QEMU delivers bytes when the host schedules it) are
# run-time options, RAM words set by -device loader: see uart.c.
set(KM_BOARD_DESCRIPTION "QEMU microbit (nRF51822, Cortex-M0): a simulated servo")
set(KM_BOARD_TOOLCHAIN arm-none-eabi)
set(KM_BOARD_BUILD_TYPE MinSizeRel)
set(KM_BOARD_COMPILE_OPTIONS -mcpu=cortex-m0 -mthumb -ffunction-sections -fdata-sections
    -fstack-usage)
set(KM_BOARD_LINK_OPTIONS -mcpu=cortex-m0 -mthumb --specs=nano.specs -nostartfiles
    -Wl,--gc-sections)
set(KM_BOARD_HOST_SOURCES)
# On the emulated bus: the boards' default 20 ms gap floor (QEMU hands bytes
# over at host speed and stalls); a conformance load run of 3,000
# transactions (on a loaded host QEMU still misses a super-ID slot about
# once in 2,000 such exchanges, README "The full load run").
set(KM_BOARD_BUS_BACKEND qemu)
set(KM_BOARD_BUS_OPTIONS)
set(KM_BOARD_BUS_LOAD 3000)
set(KM_BOARD_BUS_IMAGE boards/qemu-microbit/km-servo-qemu-microbit.elf)
