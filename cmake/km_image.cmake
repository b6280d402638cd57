# SPDX-License-Identifier: Apache-2.0
# km_add_image: one bare-metal firmware image per call, for any board.
#
#   km_add_image(NAME <name> LINKER_SCRIPT <file.ld>
#                [SOURCES <src>...] [LIBS <target>...] [DEFINES <def>...])
#
# SOURCES may be left out when a library of LIBS brings the sources (an
# interface library such as boards/sim-common's, compiled into the image).
# Emits <name>.elf (the target, named <name>), <name>.bin, <name>.hex,
# <name>.map and <name>.size next to it: the size report (arm-none-eabi-size
# and the per-module flash/RAM table of tools/check/footprint), also printed after
# each link, so the figures stay with the image they describe.
# CPU and libc flags come from the board's board.cmake, not from here.
#
# Every image is then checked by tools/check/image-check (no heap linked; static
# worst-case stack against the linker script's reserve; on boards whose
# config names RAM roots, the flash-busy interrupt paths all in RAM), with
# the board's boards/<board>/image-check.json as the written-down
# assumptions. A failed check fails the build, and keeps failing it: the
# stamp file is only written when every check passes.
include_guard(GLOBAL)
find_package(Python3 COMPONENTS Interpreter REQUIRED)

function(km_add_image)
  cmake_parse_arguments(IMG "" "NAME;LINKER_SCRIPT" "SOURCES;LIBS;DEFINES" ${ARGN})
  if(NOT IMG_NAME OR NOT IMG_LINKER_SCRIPT OR NOT (IMG_SOURCES OR IMG_LIBS))
    message(FATAL_ERROR "km_add_image: NAME, LINKER_SCRIPT and SOURCES or LIBS are required")
  endif()
  set(out ${CMAKE_CURRENT_BINARY_DIR}/${IMG_NAME})

  add_executable(${IMG_NAME} ${IMG_SOURCES})
  set_target_properties(${IMG_NAME} PROPERTIES SUFFIX ".elf" LINK_DEPENDS ${IMG_LINKER_SCRIPT})
  target_link_libraries(${IMG_NAME} PRIVATE ${IMG_LIBS})
  target_compile_definitions(${IMG_NAME} PRIVATE ${IMG_DEFINES})
  target_link_options(${IMG_NAME} PRIVATE
    -T${IMG_LINKER_SCRIPT} -Wl,-Map=${out}.map -Wl,--cref
    # Keeps the relocations in the .elf (not in .bin/.hex): image-check
    # tells a stored function address from a constant that looks like one.
    -Wl,--emit-relocs)

  add_custom_command(TARGET ${IMG_NAME} POST_BUILD
    COMMAND ${CMAKE_OBJCOPY} -O binary $<TARGET_FILE:${IMG_NAME}> ${out}.bin
    COMMAND ${CMAKE_OBJCOPY} -O ihex $<TARGET_FILE:${IMG_NAME}> ${out}.hex
    COMMAND ${CMAKE_SIZE} $<TARGET_FILE:${IMG_NAME}> > ${out}.size
    COMMAND ${Python3_EXECUTABLE} ${CMAKE_SOURCE_DIR}/tools/check/footprint ${out}.map >> ${out}.size
    COMMAND ${CMAKE_COMMAND} -E cat ${out}.size
    BYPRODUCTS ${out}.bin ${out}.hex ${out}.map ${out}.size
    COMMENT "${IMG_NAME}: .bin, .hex, .map and the size report .size"
    VERBATIM)

  set(check_cfg ${KM_BOARD_DIR}/image-check.json)
  set(check_args)
  set(check_deps)
  if(EXISTS ${check_cfg})
    # KM_BOARD_IMAGE_CHECK_ARGS: a board's extra options (stm32g031:
    # --enforce-budget when built for the 32 KiB part).
    set(check_args --config ${check_cfg} ${KM_BOARD_IMAGE_CHECK_ARGS})
    set(check_deps ${check_cfg})
  endif()
  add_custom_command(OUTPUT ${out}.check
    COMMAND ${Python3_EXECUTABLE} ${CMAKE_SOURCE_DIR}/tools/check/image-check
            $<TARGET_FILE:${IMG_NAME}> ${check_args} --su-root ${CMAKE_BINARY_DIR}
            --stamp ${out}.check
    DEPENDS ${IMG_NAME} ${CMAKE_SOURCE_DIR}/tools/check/image-check ${CMAKE_SOURCE_DIR}/tools/check/kmelf.py
            ${check_deps}
    COMMENT "${IMG_NAME}: heap, stack and flash-busy checks (tools/check/image-check)"
    VERBATIM)
  add_custom_target(${IMG_NAME}-check ALL DEPENDS ${out}.check)
endfunction()
