# SPDX-License-Identifier: Apache-2.0
# Control-quality benchmark (issue 20, docs/control-quality.md):
# bench_control (registered by the tests/bench/bench_*.c glob in
# tests/CMakeLists.txt, label "bench") runs the simulated product's
# definition, the dispatcher and control on the realistic plant; it writes
# its traces and the generated section of the doc into this build
# directory. bench_control_plot then draws one PNG per criterion with
# tools/bench/plot-control, so the script cannot rot. Both print figures and fail
# only on a broken run. tools/bench/bench-control --doc regenerates
# docs/control-quality.md from the same two programs.
if(TARGET bench_control)
  target_link_libraries(bench_control PRIVATE km_sim_product)  # the simulated product, compiled in
  set_tests_properties(bench_control PROPERTIES
    ENVIRONMENT "KM_BENCH_CONTROL_DIR=${CMAKE_CURRENT_BINARY_DIR}"
    FIXTURES_SETUP km_control_traces)
  if(EXISTS /usr/bin/python3)
    add_test(NAME bench_control_plot
      COMMAND ${CMAKE_SOURCE_DIR}/tools/bench/plot-control
              -o ${CMAKE_CURRENT_BINARY_DIR}/control-quality
              ${CMAKE_CURRENT_BINARY_DIR}/control_traces.csv)
    set_tests_properties(bench_control_plot PROPERTIES
      LABELS bench FIXTURES_REQUIRED km_control_traces)
  endif()
endif()

# Regenerates docs/control-quality.md's generated section and its PNGs
# (in the source tree: run by hand, never by CTest).
if(TARGET bench_control)
  add_custom_target(control-quality-doc
    COMMAND ${CMAKE_SOURCE_DIR}/tools/bench/bench-control --doc --build ${CMAKE_BINARY_DIR}
    DEPENDS bench_control
    WORKING_DIRECTORY ${CMAKE_SOURCE_DIR}
    USES_TERMINAL)
endif()
