# SPDX-License-Identifier: Apache-2.0
# Bus-level scenarios (tests/bus/bus_check.py): whole servos on the emulated
# bus with the plant behind them, over bytes only, on every simulated board;
# the protocol's own rules are tests/conformance.cmake's. bus_check speaks
# through the conformance suite's master (tests/conformance on PYTHONPATH)
# and starts sim/bus/servo-bus, which finds the board's build by discovery;
# KM_BUILD_DIR_<board> (a cache variable, passed on in the environment)
# points at another build tree. A missing image fails with the command that
# builds it. RUN_SERIAL: the emulators' timing should not compete with the
# other tests for two cores.
#
# smoke: one servo: the store over 0x7F after a restart, a move (0x65,
# 0x66, 0x70 for a time), host-sim's line rate past the RX queue.
# bus: three servos: a move while the others listen, one 0x83 moving all
# three to their own targets, a burst the others hear (host-sim).
# encoder: the encoder product (servo-bus --product encoder: model name,
# 0x6F turns past 360 deg, stops on 0, restart reads the angle within one
# turn) and the pot product's refusal of 0x6F, about 3 s per backend.
# protect: the protection supervisor (docs/protocol.md §5.2) driven by the
# bench scenario tests/bus/scenarios/protect.txt (supply sags, heat, loads
# on the horn): trips, releases (automatic and by 0x36), 0x64 = 5, refused
# moves and clears, the fault log over 0x7F; about 50 s per backend.
# selftest: the self-test (§5.2 0x35) with tests/bus/scenarios/selftest.txt
# (issue 18): a horn on its end stop over two restarts, an NTC that opens
# while the servo holds; about 25 s per backend.
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
  string(REPLACE "-" "_" board_id "${board}")
  km_board_build_dir(${board} dir preset)
  set(KM_BUILD_DIR_${board_id} ${dir} CACHE PATH "${board} build run by the bus tests")
  foreach(which smoke bus encoder protect selftest)
    string(REPLACE "-" "_" tname "${backend}_${which}")
    add_test(NAME bus_${tname}
      COMMAND ${KM_PYTHON3_BUS} ${CMAKE_SOURCE_DIR}/tests/bus/bus_check.py ${which} --backend ${backend}
              ${KM_BOARD_BUS_OPTIONS})
    set_tests_properties(bus_${tname} PROPERTIES LABELS bus TIMEOUT 180 RUN_SERIAL TRUE
      PASS_REGULAR_EXPRESSION "all checks passed"
      ENVIRONMENT "KM_BUILD_DIR_${board_id}=${KM_BUILD_DIR_${board_id}}"
      ENVIRONMENT_MODIFICATION "PYTHONPATH=path_list_append:${CMAKE_SOURCE_DIR}/tests/conformance")
  endforeach()
endforeach()
