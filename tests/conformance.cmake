# The conformance suite (tests/conformance/, PROTOCOL.md as the oracle) on
# the emulated buses: three servos on host-sim and on QEMU, each started on
# a free port by run_on_bus.py, which always stops the bus afterwards.
#
# Two passes on one bus: everything at 115200 baud except the checks that
# need super-ID / 0x82 answers in slot order and the load run (which mixes
# super-ID reads in); those run after the servos are switched to 9600 baud,
# as tests/bus/bus_check.py does for QEMU: emulated servos start answers when
# the host schedules them, and with three emulators and the hub on two cores
# slots 0.7 ms apart are not kept in order, 8.3 ms apart they are
# (tests/conformance/README.md has the measured rates).
#
# The load run here is 1500 transactions (printed as such); the full
# 100,000 is `tests/conformance/run_on_bus.py --backend host-sim ... --load
# 100000` (README). About 60 s per backend. RUN_SERIAL: timing-sensitive.
find_program(KM_PYTHON3_CONF python3)
if(KM_PYTHON3_CONF)
  foreach(backend host-sim qemu)
    set(extra "")
    if(backend STREQUAL "host-sim")
      set(extra --gap-floor-us 0)  # host-sim paces bytes: the real gap rule
    endif()
    string(REPLACE "-" "_" tname "${backend}")
    add_test(NAME conformance_${tname}
      COMMAND ${KM_PYTHON3_CONF} ${CMAKE_SOURCE_DIR}/tests/conformance/run_on_bus.py
              --backend ${backend} ${extra}
              --slow-baud 9600 --slow super. --slow decision:cmd.multi-read --slow load
              -- --load 1500)
    set_tests_properties(conformance_${tname} PROPERTIES
      LABELS "conformance;bus" TIMEOUT 300 RUN_SERIAL TRUE)
  endforeach()
endif()
