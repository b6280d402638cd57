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

  # Every QEMU image: no heap linked, static worst-case stack within the
  # linker script's reserve (tools/image-check, also run after each link).
  set(KM_QEMU_CHECK_BUILD_DIR ${CMAKE_SOURCE_DIR}/build/qemu CACHE PATH
      "qemu preset build whose images qemu_image_check reads")
  add_test(NAME qemu_image_check
    COMMAND ${CMAKE_COMMAND} -DPYTHON=${Python3_EXECUTABLE} -DTOOL=${CMAKE_SOURCE_DIR}/tools/image-check
            -DCONFIG=${CMAKE_SOURCE_DIR}/boards/qemu-microbit/image-check.json
            -DIMAGES=${KM_QEMU_CHECK_BUILD_DIR}/boards/qemu-microbit -DSU_ROOT=${KM_QEMU_CHECK_BUILD_DIR}
            -P ${CMAKE_SOURCE_DIR}/cmake/image_check_all.cmake)
  set_tests_properties(qemu_image_check PROPERTIES LABELS "qemu;board")
else()
  message(WARNING "qemu-system-arm or python3 missing: QEMU tests not registered")
endif()
