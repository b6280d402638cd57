# SPDX-License-Identifier: Apache-2.0
# Shared by tests/fuzz/CMakeLists.txt (libFuzzer builds) and
# tests/fuzz_replay.cmake (replay of the committed inputs in every host build).
include_guard(GLOBAL)

# The fuzz targets, one fuzz_<name>.c each (named here, not globbed).
set(KM_FUZZ_TARGETS fuzz_parser fuzz_servo fuzz_store)

# What a fuzz target links besides the pure libraries (shared with
# tests/fuzz/CMakeLists.txt): fuzz_servo the real main loop over the fake
# board (the pair twice: each calls the other), fuzz_store the app's
# user-data path (km_app_userdata.c) and the test products.
function(km_fuzz_target_links target)
  if(target MATCHES "fuzz_servo$")
    target_link_libraries(${target} PRIVATE km_fake_hal km_app km_fake_hal)
  elseif(target MATCHES "fuzz_store$")
    target_link_libraries(${target} PRIVATE km_app km_test_support)
  endif()
endfunction()

# The inputs of a target: its corpus folder, plus the §2 seeds for the
# targets whose input format starts with frames on a wire.
function(km_fuzz_inputs name out)
  set(dirs)
  if(name STREQUAL "fuzz_parser" OR name STREQUAL "fuzz_servo")
    list(APPEND dirs ${CMAKE_SOURCE_DIR}/tests/fuzz/seeds)
  endif()
  if(IS_DIRECTORY ${CMAKE_SOURCE_DIR}/tests/fuzz/corpus/${name})
    list(APPEND dirs ${CMAKE_SOURCE_DIR}/tests/fuzz/corpus/${name})
  endif()
  set(${out} ${dirs} PARENT_SCOPE)
endfunction()
