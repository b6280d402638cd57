# SPDX-License-Identifier: Apache-2.0
# A new board is boards/template copied, nothing else (tests/template_board.cmake):
#   cmake -DSOURCE=<repo> -DSCRATCH=<dir> -DBOARD=<new name> -P copy_check.cmake
# Copies the source tree (without build trees and .git) to SCRATCH/src,
# copies boards/template to boards/BOARD there, then checks that the board
# is discovered by cmake/km_boards.cmake and that a plain configure and
# build of it links its servo image and passes tools/check/image-check (the
# build's stamp). Prints "board_template_copy: ok" when every step passed.
foreach(v SOURCE SCRATCH BOARD)
  if(NOT ${v})
    message(FATAL_ERROR "copy_check.cmake: -D${v}= is required")
  endif()
endforeach()
set(src ${SCRATCH}/src)
set(bld ${SCRATCH}/build)

# Runs a command, failing the check with its output when it fails.
function(km_run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "board_template_copy: ${what} failed (${rc}):\n${out}")
  endif()
  set(km_run_out "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${SCRATCH})
file(MAKE_DIRECTORY ${src})
file(GLOB top LIST_DIRECTORIES true ${SOURCE}/*)
foreach(entry ${top})
  get_filename_component(name ${entry} NAME)
  if(NOT name STREQUAL "build")
    file(COPY ${entry} DESTINATION ${src} PATTERN .git EXCLUDE)
  endif()
endforeach()
if(EXISTS ${src}/boards/${BOARD})
  message(FATAL_ERROR "board_template_copy: boards/${BOARD} exists already")
endif()
file(COPY ${src}/boards/template/ DESTINATION ${src}/boards/${BOARD})

# Discovered as tools/test-all and tools/check/static-analysis discover boards.
km_run("board discovery" ${CMAKE_COMMAND} -P ${src}/cmake/km_boards.cmake)
string(REGEX MATCH "(^|\n)${BOARD} [^\n]*" line "${km_run_out}")
if(NOT line)
  message(FATAL_ERROR "board_template_copy: ${BOARD} not discovered:\n${km_run_out}")
endif()
message(STATUS "discovered:${line}")

km_run("configure" ${CMAKE_COMMAND} -S ${src} -B ${bld} -DKM_BOARD=${BOARD})
km_run("build" ${CMAKE_COMMAND} --build ${bld} -j2)
set(image ${bld}/boards/${BOARD}/km-servo-${BOARD})
foreach(f ${image}.elf ${image}.check)
  if(NOT EXISTS ${f})
    message(FATAL_ERROR "board_template_copy: the build made no ${f}")
  endif()
endforeach()
file(READ ${image}.size size)
message(STATUS "${size}")
file(REMOVE_RECURSE ${SCRATCH})
message(STATUS "board_template_copy: ok")
