# SPDX-License-Identifier: Apache-2.0
# Whole servos on a bus, over bytes only: the QEMU smoke test (one servo) and
# the three-servo bus test, on QEMU and on host-sim. They run the images the
# qemu and host-sim presets build (tools/test-all builds them first; a
# missing image fails with the command that builds it; KM_BUILD_QEMU /
# KM_BUILD_HOST_SIM in the environment point at other build trees).
# RUN_SERIAL: the emulators' timing should not compete with the other tests
# for two cores. The bus test checks super-ID and 0x82 answer order at
# 115200 baud on a SCHED_FIFO bus when the host allows it (servo-bus
# --realtime), else with a 20 ms emulated slot floor (bus_check.py's
# docstring; docs/protocol-decisions.md "Answer slots on emulated buses");
# the other tests run servo-bus's default scheduling (SCHED_FIFO where the
# host allows it, else plain).
#
# encoder: the encoder product (servo-bus --product encoder: model name,
# 0x6F turns past 360 deg, stops on 0, restart reads 0) and the pot
# product's refusal of 0x6F, about 3 s per backend.
#
# protect: the protection supervisor (docs/protocol.md §5.2) end to end over the
# bus, one servo driven by the bench scenario tests/bus/scenarios/protect.txt
# (servo-bus --scenario: supply sags, heat, loads on the horn): voltage,
# temperature and stall trips and releases (automatic and by 0x36), 0x64 = 5,
# refused moves and clears, and the fault log read over 0x7F; about 50 s per
# backend (the scenario's own time: 3 s detection times and releases).
#
# selftest: the self-test (docs/protocol.md §5.2 0x35) over the bus with the
# bench scenario tests/bus/scenarios/selftest.txt (issue 18): a horn pushed
# onto its end stop with the servo free, two restarts, no position fault,
# 0x64 = 2, 0x6E and a move back taken; an NTC that opens while the servo
# holds, found (0x35 bit 2), motion refused, a stop taken, the fault log;
# about 25 s per backend.
#
# The backends are the boards that name one (KM_BOARD_BUS_BACKEND in their
# board.cmake, cmake/km_boards.cmake), with the servo-bus options they give
# (KM_BOARD_BUS_OPTIONS: host-sim the real inter-byte gap rule, QEMU the
# boards' default 20 ms floor).
find_program(KM_PYTHON3_BUS python3)
km_boards_list(KM_BUS_BOARDS)
foreach(board ${KM_BUS_BOARDS})
  km_board_read(${board})
  if(NOT KM_PYTHON3_BUS OR NOT KM_BOARD_BUS_BACKEND)
    continue()
  endif()
  set(backend ${KM_BOARD_BUS_BACKEND})
  foreach(which smoke bus encoder protect selftest)
    string(REPLACE "-" "_" tname "${backend}_${which}")
    add_test(NAME bus_${tname}
      COMMAND ${KM_PYTHON3_BUS} ${CMAKE_SOURCE_DIR}/tests/bus/bus_check.py ${which} --backend ${backend}
              ${KM_BOARD_BUS_OPTIONS})
    set_tests_properties(bus_${tname} PROPERTIES LABELS bus TIMEOUT 180 RUN_SERIAL TRUE
      PASS_REGULAR_EXPRESSION "all checks passed")
  endforeach()
endforeach()
