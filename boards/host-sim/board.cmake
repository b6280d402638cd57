# SPDX-License-Identifier: Apache-2.0
# The host-sim board's declaration (cmake/km_boards.cmake): the firmware as
# a native Linux program, built with the host compiler and no CPU flags.
# The bus floors are run-time options (--gap-floor-us, --slot-floor-us,
# hs_main.c), not build settings.
set(KM_BOARD_DESCRIPTION "The firmware as a native program (software in the loop)")
set(KM_BOARD_TOOLCHAIN)
set(KM_BOARD_BUILD_TYPE Debug)
set(KM_BOARD_COMPILE_OPTIONS)
set(KM_BOARD_LINK_OPTIONS)
set(KM_BOARD_HOST_SOURCES)
# On the emulated bus: the parser's real inter-byte gap rule (its UART paces
# bytes at line rate and holds its clock for a late byte, so frames reach it
# whole); a conformance load run of 10,000 transactions.
set(KM_BOARD_BUS_BACKEND host-sim)
set(KM_BOARD_BUS_OPTIONS --gap-floor-us 0)
set(KM_BOARD_BUS_LOAD 10000)
set(KM_BOARD_BUS_IMAGE boards/host-sim/km-servo-host-sim)
