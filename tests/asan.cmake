# SPDX-License-Identifier: Apache-2.0
# Sanitizer build (preset host-asan): the store's exhaustive power-cut sweep
# takes ~5 min under ASan, so there it is replaced by its 2,000 seeded random
# histories (same invariants, ~3 s); the plain host build runs the full sweep.
if(TARGET test_store_powercut AND CMAKE_C_FLAGS MATCHES "-fsanitize=")
  add_test(NAME test_store_powercut_seeds COMMAND test_store_powercut seeds)
  set_tests_properties(test_store_powercut_seeds PROPERTIES LABELS unit)
endif()
