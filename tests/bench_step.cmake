# SPDX-License-Identifier: Apache-2.0
# Step-response benchmark and its plot (issue 7): bench_step (registered by
# the tests/bench/bench_*.c glob in tests/CMakeLists.txt) writes its traces
# into this build directory, never the source tree; bench_step_plot then
# runs tools/bench/plot-step on them so the script cannot rot. Both print
# figures/files and fail only on a broken run or an unwritable output.
# plot-step needs Debian's /usr/bin/python3 with python3-matplotlib
# (tools/install-deps).
if(TARGET bench_step AND EXISTS /usr/bin/python3)
  set_tests_properties(bench_step PROPERTIES
    ENVIRONMENT "KM_BENCH_STEP_DIR=${CMAKE_CURRENT_BINARY_DIR}"
    FIXTURES_SETUP km_step_traces)
  add_test(NAME bench_step_plot
    COMMAND ${CMAKE_SOURCE_DIR}/tools/bench/plot-step
            -o ${CMAKE_CURRENT_BINARY_DIR}/step-response.png
            ${CMAKE_CURRENT_BINARY_DIR}/step_traces.csv)
  set_tests_properties(bench_step_plot PROPERTIES
    LABELS bench FIXTURES_REQUIRED km_step_traces)
endif()
