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

# The firmware image's build-time checks, again from the host build so CI
# shows them as tests (label board): no heap, static stack within the
# linker script's reserve, and every function the bus interrupts and the
# flash driver's wait reach placed in RAM (docs/flash-busy.md). They read
# the stm32g031 preset's build; a missing image fails with the advice.
find_package(Python3 COMPONENTS Interpreter)
set(KM_STM32G031_BUILD_DIR ${CMAKE_SOURCE_DIR}/build/stm32g031 CACHE PATH
    "stm32g031 preset build read by the board tests")
if(Python3_FOUND)
  set(KM_G031_ELF ${KM_STM32G031_BUILD_DIR}/boards/stm32g031/km-servo-stm32g031.elf)
  set(KM_G031_CHECK ${Python3_EXECUTABLE} ${CMAKE_SOURCE_DIR}/tools/image-check ${KM_G031_ELF}
      --config ${KM_G031_DIR}/image-check.json --su-root ${KM_STM32G031_BUILD_DIR})
  add_test(NAME board_stm32g031_image_check COMMAND ${KM_G031_CHECK})
  # The same checks must be able to fail: a flash-resident function named
  # as a RAM root, and a stack reserve below the worst case.
  add_test(NAME board_stm32g031_ram_check_rejects_flash COMMAND ${KM_G031_CHECK}
           --checks ram --add-ram-root km_app_poll)
  add_test(NAME board_stm32g031_stack_check_rejects_small_reserve COMMAND ${KM_G031_CHECK}
           --checks stack --stack-reserve 1024)
  # Matched on the failure itself, so a missing image cannot pass them.
  set_tests_properties(board_stm32g031_ram_check_rejects_flash PROPERTIES
                       PASS_REGULAR_EXPRESSION "FAIL ram: km_app_poll \\[km_app.c.obj\\] at 0x08")
  set_tests_properties(board_stm32g031_stack_check_rejects_small_reserve PROPERTIES
                       PASS_REGULAR_EXPRESSION "FAIL stack: worst-case stack [0-9]+ B exceeds the 1024 B")
  set_tests_properties(board_stm32g031_image_check board_stm32g031_ram_check_rejects_flash
                       board_stm32g031_stack_check_rejects_small_reserve PROPERTIES LABELS board)
endif()
