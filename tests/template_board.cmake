# SPDX-License-Identifier: Apache-2.0
# boards/template is what a new board starts from: copying it must be all
# it takes. Two checks of it from the host build:
#
# 1. Compile and link check (fast, host compiler, the project's -Werror):
#    the template's hal files and product implement every hal contract and
#    the product exactly (tests/template/link_check.c calls every hal
#    function). startup.c and main.c are the MCU's; check 2 builds them.
#
# 2. board_template_copy (label board, a few minutes): a scratch copy of the
#    source tree, boards/template copied there to a new board name and
#    nothing else touched; the new board must be discovered
#    (cmake/km_boards.cmake, as tools/test-all and tools/check/static-analysis
#    find boards) and build with its own toolchain from
#    `cmake -S <copy> -B <build> -DKM_BOARD=<name>`: its servo image linked
#    and passing tools/check/image-check (tests/template/copy_check.cmake).
set(KM_TEMPLATE_DIR ${CMAKE_SOURCE_DIR}/boards/template)
file(GLOB KM_TEMPLATE_BOARD_SRC CONFIGURE_DEPENDS ${KM_TEMPLATE_DIR}/*.c)
list(REMOVE_ITEM KM_TEMPLATE_BOARD_SRC ${KM_TEMPLATE_DIR}/startup.c ${KM_TEMPLATE_DIR}/main.c)
add_library(km_board_template OBJECT ${KM_TEMPLATE_BOARD_SRC})
target_include_directories(km_board_template PUBLIC ${KM_TEMPLATE_DIR})
target_link_libraries(km_board_template PUBLIC km_app km_hal)

add_executable(km_board_template_link_check ${CMAKE_CURRENT_SOURCE_DIR}/template/link_check.c)
target_link_libraries(km_board_template_link_check PRIVATE km_board_template)

add_test(NAME board_template_copy
  COMMAND ${CMAKE_COMMAND} -DSOURCE=${CMAKE_SOURCE_DIR}
          -DSCRATCH=${CMAKE_CURRENT_BINARY_DIR}/template-copy -DBOARD=km-copied-board
          -P ${CMAKE_CURRENT_SOURCE_DIR}/template/copy_check.cmake)
set_tests_properties(board_template_copy PROPERTIES LABELS board TIMEOUT 1200
  PASS_REGULAR_EXPRESSION "board_template_copy: ok")
