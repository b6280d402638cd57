# SPDX-License-Identifier: Apache-2.0
# QEMU tests (host preset): images built by the qemu-microbit board's build
# (the qemu preset; its test images come from tests/firmware/qemu-microbit/),
# run under qemu-system-arm -M microbit. A missing image fails the test with
# that advice. Every QEMU image is also checked by
# board_qemu_microbit_image_check (tests/boards.cmake).
find_program(KM_QEMU_ARM qemu-system-arm)
find_package(Python3 COMPONENTS Interpreter)
km_board_build_dir(qemu-microbit dir preset)
set(KM_BUILD_DIR_qemu_microbit ${dir} CACHE PATH "qemu-microbit build read by the QEMU tests")
set(KM_QEMU_TEST_IMAGES ${KM_BUILD_DIR_qemu_microbit}/tests/firmware/qemu-microbit)

if(KM_QEMU_ARM AND Python3_FOUND)
  add_test(NAME qemu_board_test
    COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/qemu/run_image.py
            ${KM_QEMU_TEST_IMAGES}/km-board-test-qemu-microbit.elf 30)
  set_tests_properties(qemu_board_test PROPERTIES LABELS qemu TIMEOUT 60)

  # UART0 on a TCP socket: RX interrupt, TX and the one-shot timer end to end.
  add_test(NAME qemu_uart_echo
    COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/qemu/uart_echo.py
            ${KM_QEMU_TEST_IMAGES}/km-uart-echo-qemu-microbit.elf 30)
  set_tests_properties(qemu_uart_echo PROPERTIES LABELS qemu TIMEOUT 60)

  # The bar: no heap, no stdio, no floating point linked into any image.
  add_test(NAME qemu_image_maps
    COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/qemu/check_map.py
            ${KM_QEMU_TEST_IMAGES}/km-board-test-qemu-microbit.map
            ${KM_QEMU_TEST_IMAGES}/km-uart-echo-qemu-microbit.map)
  set_tests_properties(qemu_image_maps PROPERTIES LABELS qemu)
else()
  message(WARNING "qemu-system-arm or python3 missing: QEMU tests not registered")
endif()
