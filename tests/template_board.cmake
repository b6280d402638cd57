# Compile check of boards/template with the project's -Werror flags: the
# template must always implement every hal contract exactly.
file(GLOB KM_TEMPLATE_BOARD_SRC CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/boards/template/*.c)
add_library(km_board_template OBJECT ${KM_TEMPLATE_BOARD_SRC})
target_include_directories(km_board_template PRIVATE
  ${CMAKE_SOURCE_DIR}/boards/template ${CMAKE_SOURCE_DIR}/hal)

add_executable(km_board_template_link_check ${CMAKE_CURRENT_SOURCE_DIR}/template/link_check.c)
target_include_directories(km_board_template_link_check PRIVATE
  ${CMAKE_SOURCE_DIR}/boards/template ${CMAKE_SOURCE_DIR}/hal)
target_link_libraries(km_board_template_link_check PRIVATE km_board_template)
