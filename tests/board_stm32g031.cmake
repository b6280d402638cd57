# Host test of the STM32G031 board's pure fixed-point sensor conversions
# (the only board code that runs without the MCU).
set(KM_G031_DIR ${CMAKE_SOURCE_DIR}/boards/stm32g031)
add_executable(test_stm32g031_convert
  ${CMAKE_CURRENT_SOURCE_DIR}/board/test_stm32g031_convert.c
  ${KM_G031_DIR}/sensor_convert.c
  ${KM_G031_DIR}/board_config.c)
target_include_directories(test_stm32g031_convert PRIVATE ${KM_G031_DIR} ${CMOCKA_INCLUDE_DIR})
target_link_libraries(test_stm32g031_convert PRIVATE ${CMOCKA_LIBRARY})
add_test(NAME test_stm32g031_convert COMMAND test_stm32g031_convert)
set_tests_properties(test_stm32g031_convert PROPERTIES LABELS unit)
