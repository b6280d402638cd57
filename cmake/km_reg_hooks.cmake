# SPDX-License-Identifier: Apache-2.0
# km_reg_hooks(NAME DEF OUT_DIR): the distinct register hooks of a
# km_registers.def (tools/gen/reg-hooks) as OUT_DIR/km_reg_hooks.h, and an
# INTERFACE library NAME that a library compiling protocol/'s sources links:
# it carries OUT_DIR as an include directory (km_hooks.h includes the
# header) and builds the header before any source of its dependents.
# Generated at configure time when DEF exists then (so a configure-only
# tool, such as tools/check/static-analysis, finds it), and at build time
# whenever DEF or the generator changes (DEF may itself be a build output:
# the protocol_extend test's copy). docs/architecture.md "Register hooks".
include_guard(GLOBAL)
find_package(Python3 COMPONENTS Interpreter REQUIRED)

function(km_reg_hooks name def out_dir)
  set(gen ${CMAKE_SOURCE_DIR}/tools/gen/reg-hooks)
  set(out ${out_dir}/km_reg_hooks.h)
  if(EXISTS ${def})
    execute_process(COMMAND ${Python3_EXECUTABLE} ${gen} ${def} ${out} RESULT_VARIABLE rc)
    if(NOT rc EQUAL 0)
      message(FATAL_ERROR "km_reg_hooks: tools/gen/reg-hooks failed on ${def}")
    endif()
  endif()
  add_custom_command(OUTPUT ${out}
    COMMAND ${Python3_EXECUTABLE} ${gen} ${def} ${out}
    DEPENDS ${def} ${gen}
    COMMENT "reg-hooks: the distinct register hooks of ${def}")
  add_custom_target(${name}_gen DEPENDS ${out})
  add_library(${name} INTERFACE)
  target_include_directories(${name} INTERFACE ${out_dir})
  add_dependencies(${name} ${name}_gen)
endfunction()
