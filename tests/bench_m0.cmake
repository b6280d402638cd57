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
