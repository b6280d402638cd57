# SPDX-License-Identifier: Apache-2.0
# The STM32G031 servo board's declaration (cmake/km_boards.cmake): a
# Cortex-M0+ built with Debian's arm-none-eabi-gcc. Every object of its
# build gets one section per function/object (the 32 KiB build: per
# function, data by section anchors) so --gc-sections drops what
# is unused, and -fstack-usage: a .su file per object, the frames
# tools/check/image-check sums over the call graph to bound the stack. Links with
# newlib-nano without the C start-up files (startup.c is ours) and no heap.
set(KM_BOARD_DESCRIPTION "STM32G031 servo board (Cortex-M0+)")
set(KM_BOARD_TOOLCHAIN arm-none-eabi)
set(KM_BOARD_BUILD_TYPE MinSizeRel)
set(KM_BOARD_COMPILE_OPTIONS -mcpu=cortex-m0plus -mthumb -ffunction-sections -fdata-sections
    -fstack-usage)
# The product this board is built as (product.c) is a potentiometer servo:
# the variant is fixed at compile time (km_product_variant), so the
# encoder-only checks fold away.
list(APPEND KM_BOARD_COMPILE_OPTIONS -DKM_PRODUCT_VARIANT=KM_VARIANT_POTENTIOMETER)
set(KM_BOARD_LINK_OPTIONS -mcpu=cortex-m0plus -mthumb --specs=nano.specs --specs=nosys.specs
    -nostartfiles -Wl,--gc-sections)
# The only board code that runs without the MCU, host-tested by
# tests/board/test_stm32g031_*.c: fixed-point sensor conversions and their
# calibration, the USART divider, reset-cause decoding.
set(KM_BOARD_HOST_SOURCES sensor_convert.c board_config.c usart_brr.c reset_cause.c)
# Link-time optimisation (docs/footprint.md "LTO"): the images shrink by
# inlining and dropping across objects. The link repeats the section and
# section flags for the link-time partitions; tools/check/image-check then takes
# frames from the disassembly and tells functions apart by the source file
# the debug line table (-g: no code change) gives for them.
set(KM_G031_LTO ON CACHE BOOL "stm32g031: build and link with -flto")
if(KM_G031_LTO)
  list(APPEND KM_BOARD_COMPILE_OPTIONS -flto -g)
  list(APPEND KM_BOARD_LINK_OPTIONS -flto -Os -g -ffunction-sections -fdata-sections)
endif()
# Flash size of the part (docs/footprint.md "STM32G031F6"): 64 (G031x8,
# bootloader region 8 KiB) or 32 (G031x6 such as the 20-pin F6, bootloader
# region 4 KiB). The linker scripts and boot/boot_layout.h take the layout
# from it; tools/check/image-check prints the 32 KiB budget after every link and,
# in a 32 KiB build, fails an image over it.
set(KM_G031_FLASH_KB 64 CACHE STRING "stm32g031: flash of the part in KiB (64 or 32)")
set_property(CACHE KM_G031_FLASH_KB PROPERTY STRINGS 64 32)
if(KM_G031_FLASH_KB EQUAL 32)
  set(KM_G031_BOOT_KB 4)
  set(KM_BOARD_IMAGE_CHECK_ARGS --enforce-budget)
  # The usable stack: 1,408 B instead of the linker scripts' 1,920 (the
  # static bound is 1,208): 512 B of the 6 KiB (docs/footprint.md).
  list(APPEND KM_BOARD_LINK_OPTIONS -Wl,--defsym=KM_APP_STACK_SIZE=1408)
  # Section anchors instead of one section per object: a function reaches
  # the variables of its unit from one anchor address instead of one
  # literal word each (docs/footprint.md "Smaller without a change of
  # behaviour"). Unused variables are no longer dropped one by one; the
  # RAM is the same (3,100 B of .bss either way).
  list(TRANSFORM KM_BOARD_COMPILE_OPTIONS REPLACE "^-fdata-sections$" "-fsection-anchors")
  list(TRANSFORM KM_BOARD_LINK_OPTIONS REPLACE "^-fdata-sections$" "-fsection-anchors")
  # Loops stay loops: with the compact run-time routines a call to memset
  # or memcpy saves nothing and costs the call.
  list(APPEND KM_BOARD_COMPILE_OPTIONS -fno-tree-loop-distribute-patterns)
  list(APPEND KM_BOARD_LINK_OPTIONS -fno-tree-loop-distribute-patterns)
  # Input sections sorted by alignment: less padding between them.
  list(APPEND KM_BOARD_LINK_OPTIONS -Wl,--sort-section=alignment)
elseif(KM_G031_FLASH_KB EQUAL 64)
  set(KM_G031_BOOT_KB 8)
else()
  message(FATAL_ERROR "KM_G031_FLASH_KB must be 64 or 32, not ${KM_G031_FLASH_KB}")
endif()
# Features a 32 KiB build leaves out (docs/footprint.md "What gives way"):
# ON in the 64 KiB build, OFF in the 32 KiB one unless set on the command line.
# The compact forms (smaller, slower) are the opposite: ON only in 32 KiB.
if(KM_G031_FLASH_KB EQUAL 32)
  set(KM_G031_FEATURE_DEFAULT OFF)
  set(KM_G031_COMPACT_DEFAULT ON)
else()
  set(KM_G031_FEATURE_DEFAULT ON)
  set(KM_G031_COMPACT_DEFAULT OFF)
endif()
# The bootloader reads the store for the servo's ID and baud; without it,
# update mode answers where the application left it, else ID 1 at 115200
# (docs/update.md §3).
option(KM_G031_BOOT_STORE_READER "stm32g031 bootloader: update mode at the stored ID and baud"
       ${KM_G031_FEATURE_DEFAULT})
# A feature that gives way in the 32 KiB build (docs/footprint.md "What
# gives way"): the board option `opt`, ON by default in the 64 KiB build;
# OFF compiles the firmware with `define`=0.
function(km_g031_feature opt desc define)
  option(${opt} "${desc}" ${KM_G031_FEATURE_DEFAULT})
  if(NOT ${opt})
    set(KM_BOARD_COMPILE_OPTIONS ${KM_BOARD_COMPILE_OPTIONS} -D${define}=0 PARENT_SCOPE)
  endif()
endfunction()
# This firmware's extension command 0x7F (not in docs/protocol.md) and the
# fault log it reads, with the log's .noinit RAM; without it 0x7F is an
# unknown command (status bit 5).
km_g031_feature(KM_G031_EXT "stm32g031: extension command 0x7F and the fault log" KM_FEATURE_EXT)
# This firmware's multi-ID read 0x82 (docs/protocol.md §3 and §7 leave it
# "to be completed"; docs/protocol-decisions.md "Multi-ID read 0x82");
# without it 0x82 is an unsupported command (status bit 5, no answer).
km_g031_feature(KM_G031_MULTI_READ "stm32g031: this firmware's multi-ID read 0x82" KM_FEATURE_MULTI_READ)
# Motor mode (docs/protocol.md §5.4 0x6E, 0x70 and 0x5A = 2; docs/footprint.md
# "What gives way"): without it 0x6E and 0x70 answer as reserved addresses
# (status bit 5) and a write of 0x5A = 2 is out of range (bit 6); 0x6F, an
# encoder product's command, fails as before on this potentiometer product.
km_g031_feature(KM_G031_MOTOR_MODE "stm32g031: motor mode (0x6E, 0x70, 0x5A = 2)" KM_FEATURE_MOTOR_MODE)
# Control refinements that are not in docs/protocol.md (docs/footprint.md
# "What gives way"): a 0x68 stream's loop on the sub-count observer (else
# on the counts, as a move's), and a pushed hold's integrator refinements
# (else a still hold integrates at ki, as a moving one; docs/tuning.md).
km_g031_feature(KM_G031_STREAM_OBS "stm32g031: 0x68 streams on the sub-count observer" KM_FEATURE_STREAM_OBS)
km_g031_feature(KM_G031_HOLD_KI "stm32g031: a pushed hold's integrator refinements (ki_hold, bleeds)" KM_FEATURE_HOLD_KI)
# control/'s compact forms (one division body over a table of divisors,
# clamps not inlined, the profile's braking root through km_isqrt): fewer
# bytes, more tick instructions (docs/footprint.md). On in the 32 KiB
# build only.
option(KM_G031_CONTROL_COMPACT "stm32g031: control/'s compact forms (KM_CONTROL_COMPACT)"
       ${KM_G031_COMPACT_DEFAULT})
if(KM_G031_CONTROL_COMPACT)
  list(APPEND KM_BOARD_COMPILE_OPTIONS -DKM_CONTROL_COMPACT=1)
endif()
# protocol/'s compact forms: the parser's batch entry runs the byte rule
# on each byte instead of judging whole frames in place, and a register is
# found by a binary search instead of a 128-byte table (docs/footprint.md):
# fewer bytes, more instructions per frame. On in the 32 KiB build only.
option(KM_G031_PROTOCOL_COMPACT "stm32g031: protocol/'s compact forms (KM_PROTOCOL_COMPACT)"
       ${KM_G031_COMPACT_DEFAULT})
if(KM_G031_PROTOCOL_COMPACT)
  list(APPEND KM_BOARD_COMPILE_OPTIONS -DKM_PROTOCOL_COMPACT=1)
endif()
# The application links the bootloader's compact run-time routines
# (boot/boot_rt.c: byte-loop mem*, bit-serial division) instead of
# newlib's and libgcc's unrolled ones: smaller, slower. Off in the 64 KiB
# build, on in the 32 KiB one.
option(KM_G031_COMPACT_RT "stm32g031 application: compact mem* and division (boot/boot_rt.c)"
       ${KM_G031_COMPACT_DEFAULT})
# The application image's header: 32 B, the vector table right after it,
# instead of 256 B with the table at 0x100 (docs/update.md §2). The
# application runs on its RAM copy of the table (startup.c sets VTOR), so
# the flash table needs no VTOR alignment; the bootloader then leaves VTOR
# alone. An image format of its own: a bootloader built with it accepts only
# such images, and the other way round. On in the 32 KiB build only (the
# 64 KiB build's bootloaders in the field take 0x100).
option(KM_G031_SHORT_HEADER "stm32g031: 32-byte application header, vector table at 0x20"
       ${KM_G031_COMPACT_DEFAULT})
if(KM_G031_SHORT_HEADER)
  set(KM_G031_APP_HEADER 32)
  # No exception but reset, NMI and HardFault is taken from the flash table
  # then: it holds those and the three the drivers use
  # (28 B instead of 192), and the reset handler builds the RAM table.
  list(APPEND KM_BOARD_COMPILE_OPTIONS -DKM_G031_SHORT_VECTORS=1)
else()
  set(KM_G031_APP_HEADER 256)
endif()
list(APPEND KM_BOARD_COMPILE_OPTIONS -DKM_IMAGE_VECTORS=${KM_G031_APP_HEADER}u)
list(APPEND KM_BOARD_LINK_OPTIONS -Wl,--defsym=KM_APP_HEADER=${KM_G031_APP_HEADER})
list(APPEND KM_BOARD_COMPILE_OPTIONS -DKM_G031_FLASH_KB=${KM_G031_FLASH_KB}u -DKM_G031_BOOT_KB=${KM_G031_BOOT_KB}u)
list(APPEND KM_BOARD_LINK_OPTIONS -Wl,--defsym=KM_FLASH_SIZE=${KM_G031_FLASH_KB}K
     -Wl,--defsym=KM_BOOT_SIZE=${KM_G031_BOOT_KB}K)
