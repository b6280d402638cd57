# SPDX-License-Identifier: Apache-2.0
# docs/protocol.md holds, below its marker line, a verbatim copy of the
# protocol reading the project follows (shared/spec/PROTOCOL.md beside the
# repository), so a plain clone stands alone. This test fails with the diff
# when the copy is stale, and is skipped when the contract is not beside the
# repository (a plain clone).
set(km_contract ${CMAKE_SOURCE_DIR}/../shared/spec/PROTOCOL.md)
add_test(NAME protocol_doc_up_to_date
  COMMAND sh -c "[ -f \"$1\" ] || { echo 'no contract beside the repository: skipped'; exit 77; }; sed '1,/^<!-- verbatim below this line -->$/d' \"$2\" | diff -u \"$1\" -"
          sh ${km_contract} ${CMAKE_SOURCE_DIR}/docs/protocol.md)
set_tests_properties(protocol_doc_up_to_date PROPERTIES LABELS docs SKIP_RETURN_CODE 77)
