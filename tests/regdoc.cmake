# SPDX-License-Identifier: Apache-2.0
# docs/registers.md and docs/registers.json are generated from the register
# table (protocol/km_registers.def, units and descriptions in
# km_registers_doc.def) by tools/gen/regdoc.c and tools/gen/regdoc_json.c; these tests
# fail (and print the diff) when a checked-in file is stale.
add_executable(km_regdoc ${CMAKE_SOURCE_DIR}/tools/gen/regdoc.c ${CMAKE_SOURCE_DIR}/tools/gen/regdoc_table.c
  ${CMAKE_SOURCE_DIR}/tools/gen/regdoc_json.c)
target_link_libraries(km_regdoc PRIVATE km_protocol)
add_test(NAME regdoc_up_to_date
  COMMAND sh -c "\"$<TARGET_FILE:km_regdoc>\" | diff -u \"${CMAKE_SOURCE_DIR}/docs/registers.md\" -")
add_test(NAME regjson_up_to_date
  COMMAND sh -c "\"$<TARGET_FILE:km_regdoc>\" --json | diff -u \"${CMAKE_SOURCE_DIR}/docs/registers.json\" -")
set_tests_properties(regdoc_up_to_date regjson_up_to_date PROPERTIES LABELS docs)
