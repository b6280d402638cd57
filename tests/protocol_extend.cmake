# SPDX-License-Identifier: Apache-2.0
# Issue 19: a register is added by touching only the .def files and one
# hook (docs/architecture.md "Adding a register"). A copy of protocol/ gets
# one more register that way (tests/extend/add_register.cmake appends a row
# to each .def file; tests/extend/km_hook_demo.c is its hook); the copy is
# built as a library of its own and tests/extend/test_protocol_extend.c
# checks that every command path knows the register, and the register
# table generator (tools/gen/regdoc.c) lists it. A change that made adding a
# register need a third edit (a list of addresses in the dispatcher, a
# switch over registers) makes this test fail.
set(KM_EXT_DIR ${CMAKE_CURRENT_BINARY_DIR}/protocol_extend)
file(GLOB KM_EXT_PROTOCOL_FILES CONFIGURE_DEPENDS
  ${CMAKE_SOURCE_DIR}/protocol/*.c ${CMAKE_SOURCE_DIR}/protocol/*.h ${CMAKE_SOURCE_DIR}/protocol/*.def)
set(KM_EXT_COPIES)
set(KM_EXT_SOURCES)
foreach(f ${KM_EXT_PROTOCOL_FILES})
  get_filename_component(n ${f} NAME)
  list(APPEND KM_EXT_COPIES ${KM_EXT_DIR}/${n})
  if(n MATCHES "\\.c$")
    list(APPEND KM_EXT_SOURCES ${KM_EXT_DIR}/${n})
  endif()
endforeach()
add_custom_command(OUTPUT ${KM_EXT_COPIES}
  COMMAND ${CMAKE_COMMAND} -DSRC=${CMAKE_SOURCE_DIR}/protocol -DHERE=${CMAKE_CURRENT_SOURCE_DIR}/extend
          -DDEST=${KM_EXT_DIR} -P ${CMAKE_CURRENT_SOURCE_DIR}/extend/add_register.cmake
  DEPENDS ${KM_EXT_PROTOCOL_FILES} ${CMAKE_CURRENT_SOURCE_DIR}/extend/add_register.cmake
          ${CMAKE_CURRENT_SOURCE_DIR}/extend/rows.def ${CMAKE_CURRENT_SOURCE_DIR}/extend/rows_doc.def
  COMMENT "protocol_extend: protocol/ with one register added")
add_library(km_protocol_extended STATIC ${KM_EXT_SOURCES} ${CMAKE_CURRENT_SOURCE_DIR}/extend/km_hook_demo.c)
target_include_directories(km_protocol_extended PUBLIC ${KM_EXT_DIR})
# Its own hook lists, generated from the copy's .def as protocol/'s are
# (outside the copy: add_register.cmake empties it), once the copy is made.
add_custom_target(km_protocol_extended_copy DEPENDS ${KM_EXT_COPIES})
km_reg_hooks(km_protocol_extended_hooks ${KM_EXT_DIR}/km_registers.def ${CMAKE_CURRENT_BINARY_DIR}/protocol_extend_gen)
add_dependencies(km_protocol_extended_hooks_gen km_protocol_extended_copy)
target_link_libraries(km_protocol_extended PUBLIC km_shared km_protocol_extended_hooks)

add_executable(test_protocol_extend ${CMAKE_CURRENT_SOURCE_DIR}/extend/test_protocol_extend.c)
target_link_libraries(test_protocol_extend PRIVATE km_protocol_extended km_test_support ${CMOCKA_LIBRARY})
add_test(NAME test_protocol_extend COMMAND test_protocol_extend)
set_tests_properties(test_protocol_extend PROPERTIES LABELS unit)

# The generated register table lists it, from the two rows alone.
add_executable(km_regdoc_extended ${CMAKE_SOURCE_DIR}/tools/gen/regdoc.c ${CMAKE_SOURCE_DIR}/tools/gen/regdoc_table.c
  ${CMAKE_SOURCE_DIR}/tools/gen/regdoc_json.c)
target_link_libraries(km_regdoc_extended PRIVATE km_protocol_extended)
add_test(NAME protocol_extend_regdoc
  COMMAND sh -c "\"$<TARGET_FILE:km_regdoc_extended>\" | grep -q '^| 0x71 | DEMO_ACCUMULATE | RW |' && \"$<TARGET_FILE:km_regdoc_extended>\" --json | grep -q '\"name\": \"demo_accumulate\"'")
set_tests_properties(protocol_extend_regdoc PROPERTIES LABELS unit)
