# Host tests of the STM32G031 board's pure parts (the only board code that
# runs without the MCU): fixed-point sensor conversions, USART divider,
# reset-cause decoding.
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

# RCC_CSR flags + fault record -> km_reset_cause_t (the pure part of fault.c).
add_executable(test_stm32g031_reset_cause
  ${CMAKE_CURRENT_SOURCE_DIR}/board/test_stm32g031_reset_cause.c
  ${KM_G031_DIR}/reset_cause.c)
target_include_directories(test_stm32g031_reset_cause PRIVATE ${KM_G031_DIR}
  ${CMAKE_SOURCE_DIR}/hal ${CMOCKA_INCLUDE_DIR})
target_link_libraries(test_stm32g031_reset_cause PRIVATE ${CMOCKA_LIBRARY})
add_test(NAME test_stm32g031_reset_cause COMMAND test_stm32g031_reset_cause)
set_tests_properties(test_stm32g031_reset_cause PROPERTIES LABELS unit)
