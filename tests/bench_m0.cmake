# SPDX-License-Identifier: Apache-2.0
# Cortex-M0 instruction counts of the firmware's hot paths (parser per byte,
# dispatcher per command, flash commit, control tick), exact, in QEMU
# (tools/bench/bench-m0: -singlestep -d exec,nochain, validated on a loop of known
# length). Prints figures and targets; fails only on a missing measurement,
# a failed check in the image or a validation count that is off. Reads the
# image from build/qemu (or $KM_BENCH_M0_BUILD), as tools/test-all builds it.
find_program(KM_PYTHON3_BENCH_M0 python3)
if(KM_PYTHON3_BENCH_M0)
  add_test(NAME bench_m0_qemu COMMAND ${KM_PYTHON3_BENCH_M0} ${CMAKE_SOURCE_DIR}/tools/bench/bench-m0)
  set_tests_properties(bench_m0_qemu PROPERTIES LABELS bench TIMEOUT 300)
endif()
# The real path on the shipped stm32g031 image (tests/bench/m0/bench_realpath.py,
# docs/benchmarks.md): bytes through USART1's interrupt, queue and main loop,
# the control tick with the board's sensors, 0x83/0x82 lists, on sim/g031, in
# instructions and estimated M0+ cycles. Needs the stm32g031 preset built
# first; fails when a byte inside a frame runs the parser, a control tick calls
# a library division or a list scan costs more an entry than LIST_ENTRY_MAX.
find_program(KM_DEBIAN_PYTHON_BENCH NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(KM_DEBIAN_PYTHON_BENCH)
  add_test(NAME bench_realpath_g031
    COMMAND ${KM_DEBIAN_PYTHON_BENCH} ${CMAKE_SOURCE_DIR}/tests/bench/m0/bench_realpath.py
            ${CMAKE_SOURCE_DIR}/build/stm32g031/boards/stm32g031 --check --step 8
            --json ${CMAKE_BINARY_DIR}/bench-realpath.json)
  set_tests_properties(bench_realpath_g031 PROPERTIES LABELS bench TIMEOUT 900)
endif()
# docs/figures.md is generated (tests/bench/m0/figures.py, goal 7 of issue 21):
# fails when the committed file is not what the stm32g031 image and this
# build's bench_store_wear (the store's wear) and the 32 KiB build measure
# now; fails, never skips, when bench_store_wear or the 32 KiB build is missing.
if(KM_DEBIAN_PYTHON_BENCH)
  add_test(NAME figures_doc_current
    COMMAND ${KM_DEBIAN_PYTHON_BENCH} ${CMAKE_SOURCE_DIR}/tests/bench/m0/figures.py
            --build ${CMAKE_SOURCE_DIR}/build/stm32g031 --host-build ${CMAKE_BINARY_DIR}
            --f6-build ${CMAKE_BINARY_DIR}/f6-fit --check)
  # The 32 KiB budget lines come from the build board_stm32g031_f6_fit makes
  # (tests/boards.cmake): that test runs first, even under -R.
  set_tests_properties(figures_doc_current PROPERTIES LABELS bench TIMEOUT 900
    FIXTURES_REQUIRED km_f6_fit_build)
  # Both import the virtual G031 (sim/g031) beside what tests/CMakeLists.txt
  # puts on PYTHONPATH for every test.
  set_property(TEST bench_realpath_g031 figures_doc_current APPEND PROPERTY ENVIRONMENT_MODIFICATION
    "PYTHONPATH=path_list_append:${CMAKE_SOURCE_DIR}/sim/g031")
endif()
