# The conformance suite (tests/conformance/, PROTOCOL.md as the oracle) on
# the emulated buses: three servos on host-sim and on QEMU, each started on
# a free port by run_on_bus.py, which always stops the bus afterwards.
#
# Every one of the 182 checks runs, once: run_on_bus.py names them to the
# suite one by one and fails a check with no result ("not run"); its last
# line is "total: N passed, M failed, K skipped", each skip listed above it
# with its reason. Where the host allows SCHED_FIFO (root on CI), the bus
# runs with servo-bus --realtime and every check, the super-ID / 0x82 slot
# order and the load run included, runs at 115200 baud in one pass: emulated
# answers then keep the real slot rule (docs/protocol-decisions.md "Answer
# slots on emulated buses"). Elsewhere (servo-bus --no-realtime), two passes
# on one bus: everything at 115200 except the --slow checks, which run after
# the servos are switched to 9600 baud (slots 8.3 ms apart;
# tests/conformance/README.md has the measured rates).
#
# The load run here is 10,000 transactions on host-sim and 3,000 on QEMU
# (printed as such: QEMU on a loaded host still misses a super-ID slot about
# once in 2,000 such exchanges, README "The full load run"); the full
# 100,000 is `tests/conformance/run_on_bus.py --backend host-sim
# --gap-floor-us 0 -- --only load --load 100000` (README). About 50-60 s
# per backend. RUN_SERIAL: timing-sensitive.
find_program(KM_PYTHON3_CONF python3)
if(KM_PYTHON3_CONF)
  foreach(backend host-sim qemu)
    set(extra "")
    set(load 3000)
    if(backend STREQUAL "host-sim")
      set(extra --gap-floor-us 0)  # host-sim paces bytes: the real gap rule
      set(load 10000)
    endif()
    string(REPLACE "-" "_" tname "${backend}")
    add_test(NAME conformance_${tname}
      COMMAND ${KM_PYTHON3_CONF} ${CMAKE_SOURCE_DIR}/tests/conformance/run_on_bus.py
              --backend ${backend} ${extra}
              --slow-baud 9600 --slow super. --slow decision:cmd.multi-read --slow load
              -- --load ${load})
    set_tests_properties(conformance_${tname} PROPERTIES
      LABELS "conformance;bus" TIMEOUT 420 RUN_SERIAL TRUE)
  endforeach()
endif()
