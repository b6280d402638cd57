# SPDX-License-Identifier: Apache-2.0
# Boards, discovered: every folder boards/<name>/ with a board.cmake is a
# board called <name>. boards/template/ is the pattern a new board copies
# (and nothing else: docs/architecture.md "Boards and the build"), not a
# board of its own; tests/template_board.cmake builds a copy of it under
# another name.
#
# A board.cmake only sets variables, so it can be read before project()
# (the top-level CMakeLists.txt takes the toolchain from it) and by scripts:
#   KM_BOARD_DESCRIPTION      one line: what the board is
#   KM_BOARD_TOOLCHAIN        cmake/<name>.cmake cross toolchain; empty: the host compiler
#   KM_BOARD_BUILD_TYPE       its default CMAKE_BUILD_TYPE
#   KM_BOARD_COMPILE_OPTIONS  added to every object of its build (CPU flags...)
#   KM_BOARD_LINK_OPTIONS     added to every link of its build
#   KM_BOARD_HOST_SOURCES     its pure parts (files of boards/<name>/): the host
#                             build compiles them into km_board_host_<name> for
#                             the tests tests/board/test_<name>_*.c (tests/boards.cmake)
#   KM_BOARD_BUS_BACKEND      a simulated board: the sim/bus/servo-bus --backend that
#                             runs it; the bus and conformance tests run on every
#                             board that names one (tests/bus.cmake, tests/conformance.cmake)
#   KM_BOARD_BUS_OPTIONS      the servo-bus options those tests give it
#   KM_BOARD_BUS_LOAD         the transactions of the conformance load run on it
#   KM_BOARD_BUS_IMAGE        the servo image servo-bus runs, relative to the board's build tree
# Its CMakeLists.txt then builds the board (km_board and its images).
#
# Included by CMakeLists.txt and tests/; run as a script it prints one line
# per board, "<name> <build dir> <preset or -> <toolchain or ->", for
# tools/test-all and tools/check/static-analysis:
#   cmake -P cmake/km_boards.cmake
# The build dir is the binaryDir of the CMakePresets.json configure preset
# whose KM_BOARD names the board, else build/<name>.
# With -DKM_BOARDS_QUERY=bus it prints one line per simulated board instead,
# "<bus backend> <name> <build dir> <preset or -> <image>", for sim/bus/servo-bus:
#   cmake -DKM_BOARDS_QUERY=bus -P cmake/km_boards.cmake
include_guard(GLOBAL)
get_filename_component(KM_ROOT_DIR ${CMAKE_CURRENT_LIST_DIR}/.. ABSOLUTE)

set(KM_BOARD_VARIABLES KM_BOARD_DESCRIPTION KM_BOARD_TOOLCHAIN KM_BOARD_BUILD_TYPE
    KM_BOARD_COMPILE_OPTIONS KM_BOARD_LINK_OPTIONS KM_BOARD_HOST_SOURCES
    KM_BOARD_BUS_BACKEND KM_BOARD_BUS_OPTIONS KM_BOARD_BUS_LOAD KM_BOARD_BUS_IMAGE)

# The discovered boards' names, sorted, into `out`.
function(km_boards_list out)
  file(GLOB decls RELATIVE ${KM_ROOT_DIR}/boards ${KM_ROOT_DIR}/boards/*/board.cmake)
  set(names)
  foreach(d ${decls})
    get_filename_component(name ${d} DIRECTORY)
    if(NOT name STREQUAL "template")
      list(APPEND names ${name})
    endif()
  endforeach()
  list(SORT names)
  set(${out} ${names} PARENT_SCOPE)
endfunction()

# Reads boards/<name>/board.cmake into the caller's KM_BOARD_* variables
# (a macro: its variables land in the caller's scope); fails on no board.
macro(km_board_read name)
  foreach(v ${KM_BOARD_VARIABLES})
    unset(${v})
  endforeach()
  if(NOT EXISTS ${KM_ROOT_DIR}/boards/${name}/board.cmake)
    km_boards_list(_km_known)
    message(FATAL_ERROR "KM_BOARD=${name}: no boards/${name}/board.cmake "
                        "(boards: host ${_km_known})")
  endif()
  include(${KM_ROOT_DIR}/boards/${name}/board.cmake)
endmacro()

# The build tree of board `name` and the preset that makes it ("-" when
# none): the CMakePresets.json configure preset whose KM_BOARD is `name`.
function(km_board_build_dir name out_dir out_preset)
  set(dir ${KM_ROOT_DIR}/build/${name})
  set(preset "-")
  file(READ ${KM_ROOT_DIR}/CMakePresets.json presets_json)
  string(JSON n LENGTH "${presets_json}" configurePresets)
  math(EXPR last "${n} - 1")
  foreach(i RANGE ${last})
    string(JSON board ERROR_VARIABLE no_board GET "${presets_json}" configurePresets ${i}
           cacheVariables KM_BOARD)
    if(NOT no_board AND board STREQUAL name)
      string(JSON preset GET "${presets_json}" configurePresets ${i} name)
      string(JSON dir GET "${presets_json}" configurePresets ${i} binaryDir)
      string(REPLACE "\${sourceDir}" "${KM_ROOT_DIR}" dir "${dir}")
      break()
    endif()
  endforeach()
  set(${out_dir} ${dir} PARENT_SCOPE)
  set(${out_preset} ${preset} PARENT_SCOPE)
endfunction()

# Script mode: the list for the tools.
if(CMAKE_SCRIPT_MODE_FILE STREQUAL CMAKE_CURRENT_LIST_FILE)
  km_boards_list(names)
  foreach(name ${names})
    km_board_read(${name})
    km_board_build_dir(${name} dir preset)
    if(KM_BOARDS_QUERY STREQUAL "bus")
      if(KM_BOARD_BUS_BACKEND)
        execute_process(COMMAND ${CMAKE_COMMAND} -E echo
                        "${KM_BOARD_BUS_BACKEND} ${name} ${dir} ${preset} ${KM_BOARD_BUS_IMAGE}")
      endif()
      continue()
    endif()
    set(toolchain "-")
    if(KM_BOARD_TOOLCHAIN)
      set(toolchain ${KM_BOARD_TOOLCHAIN})
    endif()
    execute_process(COMMAND ${CMAKE_COMMAND} -E echo "${name} ${dir} ${preset} ${toolchain}")
  endforeach()
endif()
