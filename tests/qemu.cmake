# QEMU tests (host preset): images built by the qemu preset, run under
# qemu-system-arm -M microbit. They read build/qemu, so the qemu preset must
# be built first; a missing image fails the test with that advice.
find_program(KM_QEMU_ARM qemu-system-arm)
find_package(Python3 COMPONENTS Interpreter)
set(KM_QEMU_IMAGES ${CMAKE_SOURCE_DIR}/build/qemu/boards/qemu-microbit)

if(KM_QEMU_ARM AND Python3_FOUND)
  add_test(NAME qemu_board_test
    COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/qemu/run_image.py
            ${KM_QEMU_IMAGES}/km-board-test-qemu-microbit.elf 30)
  set_tests_properties(qemu_board_test PROPERTIES LABELS qemu TIMEOUT 60)

  # UART0 on a TCP socket: RX interrupt, TX and the one-shot timer end to end.
  add_test(NAME qemu_uart_echo
    COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/qemu/uart_echo.py
            ${KM_QEMU_IMAGES}/km-uart-echo-qemu-microbit.elf 30)
  set_tests_properties(qemu_uart_echo PROPERTIES LABELS qemu TIMEOUT 60)

  # The bar: no heap, no stdio, no floating point linked into any image.
  add_test(NAME qemu_image_maps
    COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_SOURCE_DIR}/qemu/check_map.py
            ${KM_QEMU_IMAGES}/km-board-test-qemu-microbit.map
            ${KM_QEMU_IMAGES}/km-uart-echo-qemu-microbit.map)
  set_tests_properties(qemu_image_maps PROPERTIES LABELS qemu)
else()
  message(WARNING "qemu-system-arm or python3 missing: QEMU tests not registered")
endif()
