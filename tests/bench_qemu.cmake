# SPDX-License-Identifier: Apache-2.0
# Answer-delay accuracy of the firmware in QEMU under -icount (virtual time,
# deterministic): prints the figures, fails only if an answer starts more
# than one byte time (115200 baud) away from its configured delay.
find_program(KM_PYTHON3_BENCH python3)
if(KM_PYTHON3_BENCH)
  add_test(NAME bench_answer_delay_qemu COMMAND ${KM_PYTHON3_BENCH} ${CMAKE_SOURCE_DIR}/tools/bench/bench-answer-delay)
  set_tests_properties(bench_answer_delay_qemu PROPERTIES LABELS bench TIMEOUT 300 RUN_SERIAL TRUE)
endif()
