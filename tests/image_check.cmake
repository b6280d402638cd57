# SPDX-License-Identifier: Apache-2.0
# tools/check/image-check must be able to fail: run on the stm32g031 servo image
# (the board whose image-check.json names flash-busy RAM roots, so all three
# checks apply), once with a flash-resident function named as a RAM root and
# once with a stack reserve below the worst case. Matched on the failure
# itself, so a missing image cannot pass them. They read the board's build
# (the cache variable KM_BUILD_DIR_stm32g031, as tests/boards.cmake).
find_package(Python3 COMPONENTS Interpreter REQUIRED)
km_board_build_dir(stm32g031 dir preset)
set(KM_BUILD_DIR_stm32g031 ${dir} CACHE PATH "stm32g031 build read by board_stm32g031_image_check")
set(KM_G031_ELF ${KM_BUILD_DIR_stm32g031}/boards/stm32g031/km-servo-stm32g031.elf)
set(KM_G031_CHECK ${Python3_EXECUTABLE} ${CMAKE_SOURCE_DIR}/tools/check/image-check ${KM_G031_ELF}
    --config ${CMAKE_SOURCE_DIR}/boards/stm32g031/image-check.json --su-root ${KM_BUILD_DIR_stm32g031})
add_test(NAME board_stm32g031_ram_check_rejects_flash COMMAND ${KM_G031_CHECK}
         --checks ram --add-ram-root km_app_poll)
add_test(NAME board_stm32g031_stack_check_rejects_small_reserve COMMAND ${KM_G031_CHECK}
         --checks stack --stack-reserve 1024)
set_tests_properties(board_stm32g031_ram_check_rejects_flash PROPERTIES
                     PASS_REGULAR_EXPRESSION "FAIL ram: km_app_poll \\[km_app.c(.obj|, LTO)\\] at 0x08")
set_tests_properties(board_stm32g031_stack_check_rejects_small_reserve PROPERTIES
                     PASS_REGULAR_EXPRESSION "FAIL stack: worst-case stack [0-9]+ B exceeds the 1024 B")
set_tests_properties(board_stm32g031_ram_check_rejects_flash
                     board_stm32g031_stack_check_rejects_small_reserve PROPERTIES LABELS board)
