# SPDX-License-Identifier: Apache-2.0
# Replays every committed fuzz input (tests/fuzz/README.md: the §2 seeds,
# tests/fuzz/corpus/<target>/ with its regress_* findings) through each fuzz
# target, in every host build, as CTest tests fuzz_replay_<target> (label
# unit, so the ASan build replays them under the sanitizers too). Without
# the fuzz preset the target's entry point is linked to a small main
# (tests/fuzz/fuzz_replay_main.c); in the fuzz preset libFuzzer replays
# (-runs=0: run the given inputs once, no fuzzing).
set(KM_FUZZ_DIR ${CMAKE_CURRENT_SOURCE_DIR}/fuzz)

include(${KM_FUZZ_DIR}/targets.cmake)

foreach(name ${KM_FUZZ_TARGETS})
  set(src ${KM_FUZZ_DIR}/${name}.c)
  km_fuzz_inputs(${name} dirs)
  if(KM_FUZZ)
    set(inputs)
    foreach(d ${dirs})
      file(GLOB f CONFIGURE_DEPENDS LIST_DIRECTORIES false ${d}/*)
      list(APPEND inputs ${f})
    endforeach()
    add_test(NAME fuzz_replay_${name} COMMAND ${name} -runs=0 ${inputs})
  else()
    add_executable(replay_${name} ${src} ${KM_FUZZ_DIR}/fuzz_replay_main.c)
    target_link_libraries(replay_${name} PRIVATE ${KM_TEST_LIBS})
    km_fuzz_target_links(replay_${name})
    add_test(NAME fuzz_replay_${name} COMMAND replay_${name} ${dirs})
  endif()
  set_tests_properties(fuzz_replay_${name} PROPERTIES LABELS unit)
endforeach()
