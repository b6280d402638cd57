# Whole servos on a bus, over bytes only: the QEMU smoke test (one servo) and
# the three-servo bus test, on QEMU and on host-sim. They run the images the
# qemu and host-sim presets build (tools/test-all builds them first; a
# missing image fails with the command that builds it). RUN_SERIAL: the
# emulators' timing should not compete with the other tests for two cores.
find_program(KM_PYTHON3_BUS python3)
if(KM_PYTHON3_BUS)
  foreach(backend qemu host-sim)
    foreach(which smoke bus)
      string(REPLACE "-" "_" tname "${backend}_${which}")
      add_test(NAME bus_${tname}
        COMMAND ${KM_PYTHON3_BUS} ${CMAKE_SOURCE_DIR}/tests/bus/bus_check.py ${which} --backend ${backend})
      set_tests_properties(bus_${tname} PROPERTIES LABELS bus TIMEOUT 180 RUN_SERIAL TRUE
        PASS_REGULAR_EXPRESSION "all checks passed")
    endforeach()
  endforeach()
endif()
