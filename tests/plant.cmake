# SPDX-License-Identifier: Apache-2.0
# The plant tests compute expected physics with libm on the host (the plant
# itself is integer-only).
foreach(t test_plant test_plant_real)
  if(TARGET ${t})
    target_link_libraries(${t} PRIVATE m)
  endif()
endforeach()

# The plant also runs in the Cortex-M0 QEMU image: check that bar from the
# host build (skipped when no ARM cross compiler is installed).
find_program(KM_ARM_GCC arm-none-eabi-gcc)
if(KM_ARM_GCC)
  add_test(NAME plant_m0_bar
    COMMAND sh ${CMAKE_SOURCE_DIR}/sim/plant/check_m0.sh ${KM_ARM_GCC} ${CMAKE_SOURCE_DIR}/sim/plant)
  set_tests_properties(plant_m0_bar PROPERTIES LABELS unit)
endif()
