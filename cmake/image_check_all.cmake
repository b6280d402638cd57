# SPDX-License-Identifier: Apache-2.0
# Runs tools/check/image-check on every *.elf of one board's build tree (ctest -P
# script): fails if the tree holds no image or any image fails.
#   cmake -DPYTHON=… -DTOOL=… -DCONFIG=… -DIMAGES=<build dir> -DSU_ROOT=<build>
#         [-DBOARD=<board>] -P image_check_all.cmake
file(GLOB_RECURSE elfs ${IMAGES}/*.elf)
list(FILTER elfs EXCLUDE REGEX "/CMakeFiles/")
if(NOT elfs)
  message(FATAL_ERROR "no image in ${IMAGES}: build the board first "
                      "(cmake -S . -B ${IMAGES} -DKM_BOARD=${BOARD}, or its preset)")
endif()
set(config)
if(EXISTS ${CONFIG})
  set(config --config ${CONFIG})
endif()
set(failed)
foreach(elf ${elfs})
  execute_process(COMMAND ${PYTHON} ${TOOL} ${elf} ${config} --su-root ${SU_ROOT}
                  RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    list(APPEND failed ${elf})
  endif()
endforeach()
if(failed)
  message(FATAL_ERROR "image-check failed: ${failed}")
endif()
