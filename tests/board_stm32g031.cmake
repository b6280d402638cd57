# Host tests of the STM32G031 board's pure parts (the only board code that
# runs without the MCU): fixed-point sensor conversions, USART divider.
set(KM_G031_DIR ${CMAKE_SOURCE_DIR}/boards/stm32g031)
add_executable(test_stm32g031_convert
  ${CMAKE_CURRENT_SOURCE_DIR}/board/test_stm32g031_convert.c
  ${KM_G031_DIR}/sensor_convert.c
  ${KM_G031_DIR}/board_config.c)
target_include_directories(test_stm32g031_convert PRIVATE ${KM_G031_DIR} ${CMOCKA_INCLUDE_DIR})
target_link_libraries(test_stm32g031_convert PRIVATE ${CMOCKA_LIBRARY})
add_test(NAME test_stm32g031_convert COMMAND test_stm32g031_convert)
set_tests_properties(test_stm32g031_convert PROPERTIES LABELS unit)

add_executable(test_stm32g031_brr
  ${CMAKE_CURRENT_SOURCE_DIR}/board/test_stm32g031_brr.c
  ${KM_G031_DIR}/usart_brr.c)
target_include_directories(test_stm32g031_brr PRIVATE ${KM_G031_DIR} ${CMOCKA_INCLUDE_DIR})
target_link_libraries(test_stm32g031_brr PRIVATE ${CMOCKA_LIBRARY})
add_test(NAME test_stm32g031_brr COMMAND test_stm32g031_brr)
set_tests_properties(test_stm32g031_brr PROPERTIES LABELS unit)
