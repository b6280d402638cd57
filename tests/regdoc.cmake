# docs/registers.md is generated from the register table by tools/regdoc.c;
# this test fails (and prints the diff) when the checked-in file is stale.
add_executable(km_regdoc ${CMAKE_SOURCE_DIR}/tools/regdoc.c)
target_link_libraries(km_regdoc PRIVATE km_protocol)
add_test(NAME regdoc_up_to_date
  COMMAND sh -c "\"$<TARGET_FILE:km_regdoc>\" | diff -u \"${CMAKE_SOURCE_DIR}/docs/registers.md\" -")
set_tests_properties(regdoc_up_to_date PROPERTIES LABELS docs)
