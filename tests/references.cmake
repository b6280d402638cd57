# SPDX-License-Identifier: Apache-2.0
# Every reference inside the repository resolves (tools/check/references):
# paths to the repository's files, Markdown links, and quoted sections of
# its documents. About 1 s of CPU; fails naming each one that does not.
find_program(KM_PYTHON3_REFS python3)
add_test(NAME references_resolve COMMAND ${KM_PYTHON3_REFS} ${CMAKE_SOURCE_DIR}/tools/check/references
                                         ${CMAKE_SOURCE_DIR})
set_tests_properties(references_resolve PROPERTIES LABELS docs)
