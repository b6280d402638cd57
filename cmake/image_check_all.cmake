# Runs tools/image-check on every *.elf of one image directory (ctest -P
# script): fails if the directory holds no image or any image fails.
#   cmake -DPYTHON=… -DTOOL=… -DCONFIG=… -DIMAGES=<dir> -DSU_ROOT=<build> -P image_check_all.cmake
file(GLOB elfs ${IMAGES}/*.elf)
if(NOT elfs)
  message(FATAL_ERROR "no image in ${IMAGES}: build the ARM preset first")
endif()
set(failed)
foreach(elf ${elfs})
  execute_process(COMMAND ${PYTHON} ${TOOL} ${elf} --config ${CONFIG} --su-root ${SU_ROOT}
                  RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    list(APPEND failed ${elf})
  endif()
endforeach()
if(failed)
  message(FATAL_ERROR "image-check failed: ${failed}")
endif()
