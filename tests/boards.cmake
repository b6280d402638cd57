# SPDX-License-Identifier: Apache-2.0
# Every board found by cmake/km_boards.cmake, from the host build:
#
# 1. Its pure parts, the board.cmake's KM_BOARD_HOST_SOURCES (code that runs
#    without the MCU: conversions, dividers, decoders), compiled for the host
#    as km_board_host_<board>, and every tests/board/test_<board>_*.c a
#    cmocka test that links it (label unit; '-' in a board's name is '_'
#    in the file's). A test file with no such board, or a board whose host
#    sources no test links, fails the configure: nothing goes untested
#    without a word.
#
# 2. A board with a cross toolchain builds images: board_<board>_image_check
#    runs tools/check/image-check again on every image of its build tree (no heap,
#    stack within the linker script's reserve, the flash-busy RAM rule where
#    the board's image-check.json names RAM roots), so CI shows the
#    build-time checks as tests (label board). It reads the board's build
#    (its preset's binaryDir, else build/<board>; the cache variable
#    KM_BUILD_DIR_<board, - as _> points elsewhere); no image fails with the advice.
find_package(Python3 COMPONENTS Interpreter REQUIRED)

km_boards_list(KM_BOARDS)
file(GLOB KM_BOARD_TEST_SRCS CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/board/test_*.c)
set(KM_BOARD_TESTS_CLAIMED)
foreach(board ${KM_BOARDS})
  string(REPLACE "-" "_" board_id ${board})
  km_board_read(${board})

  file(GLOB tests CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/board/test_${board_id}_*.c)
  list(APPEND KM_BOARD_TESTS_CLAIMED ${tests})
  if(KM_BOARD_HOST_SOURCES AND NOT tests)
    message(FATAL_ERROR "boards/${board}: KM_BOARD_HOST_SOURCES but no tests/board/test_${board_id}_*.c")
  endif()
  if(tests AND NOT KM_BOARD_HOST_SOURCES)
    message(FATAL_ERROR "tests/board/test_${board_id}_*.c: boards/${board} declares no KM_BOARD_HOST_SOURCES")
  endif()
  if(tests)
    list(TRANSFORM KM_BOARD_HOST_SOURCES PREPEND ${KM_ROOT_DIR}/boards/${board}/)
    add_library(km_board_host_${board_id} STATIC ${KM_BOARD_HOST_SOURCES})
    target_include_directories(km_board_host_${board_id} PUBLIC ${KM_ROOT_DIR}/boards/${board})
    target_link_libraries(km_board_host_${board_id} PUBLIC km_hal)
    foreach(src ${tests})
      get_filename_component(name ${src} NAME_WE)
      add_executable(${name} ${src})
      target_link_libraries(${name} PRIVATE km_board_host_${board_id} km_test_support ${CMOCKA_LIBRARY})
      add_test(NAME ${name} COMMAND ${name})
      set_tests_properties(${name} PROPERTIES LABELS unit)
    endforeach()
  endif()

  if(KM_BOARD_TOOLCHAIN)
    km_board_build_dir(${board} dir preset)
    set(KM_BUILD_DIR_${board_id} ${dir} CACHE PATH "${board} build read by board_${board_id}_image_check")
    add_test(NAME board_${board_id}_image_check
      COMMAND ${CMAKE_COMMAND} -DPYTHON=${Python3_EXECUTABLE} -DTOOL=${CMAKE_SOURCE_DIR}/tools/check/image-check
              -DCONFIG=${KM_ROOT_DIR}/boards/${board}/image-check.json
              -DIMAGES=${KM_BUILD_DIR_${board_id}} -DSU_ROOT=${KM_BUILD_DIR_${board_id}}
              -DBOARD=${board}
              -P ${CMAKE_SOURCE_DIR}/cmake/image_check_all.cmake)
    set_tests_properties(board_${board_id}_image_check PROPERTIES LABELS board)
  endif()
endforeach()

list(REMOVE_ITEM KM_BOARD_TEST_SRCS ${KM_BOARD_TESTS_CLAIMED})
if(KM_BOARD_TEST_SRCS)
  message(FATAL_ERROR "tests/board/: no board for ${KM_BOARD_TEST_SRCS} (test_<board>_*.c)")
endif()

# The 32 KiB STM32G031F6 build keeps fitting (docs/footprint.md
# "STM32G031F6"): its own configure and build of the images held to the
# budget (image-check --enforce-budget: the bootloader, the application in
# its layout, the image without bootloader), the bootloader alone on the
# virtual G031 answering at ID 1 (docs/update.md §3), the bootloader
# starting the application's update image, which answers at ID 0, and the
# servo image without bootloader answering at ID 0: about 40 s. Debian's
# python3, which has the virtual G031's python3-unicorn (tests/g031.cmake).
find_program(KM_DEBIAN_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
add_test(NAME board_stm32g031_f6_fit
  COMMAND ${KM_DEBIAN_PYTHON} ${KM_ROOT_DIR}/tests/footprint/f6_fit.py ${KM_ROOT_DIR}
          ${CMAKE_BINARY_DIR}/f6-fit)
set_tests_properties(board_stm32g031_f6_fit PROPERTIES LABELS board TIMEOUT 900
  FIXTURES_SETUP km_f6_fit_build)  # its build dir feeds figures_doc_current (tests/bench_m0.cmake)
set_property(TEST board_stm32g031_f6_fit APPEND PROPERTY ENVIRONMENT_MODIFICATION
  "PYTHONPATH=path_list_append:${KM_ROOT_DIR}/sim/g031")  # the virtual G031
# kmx monitor's samples (host/kmx cli.monitor_sample, also the web live
# view) on two virtual G031s running that build's servo image, which has no
# 0x82: after the first sample's refused 0x82 (status bit 5 once) kmx reads
# them by 0x02 only, so later samples show no bit 5 (Registers.read_each):
# about 5 s after the build.
add_test(NAME board_stm32g031_f6_kmx_monitor
  COMMAND ${KM_DEBIAN_PYTHON} ${KM_ROOT_DIR}/tests/footprint/f6_monitor.py ${CMAKE_BINARY_DIR}/f6-fit)
set_tests_properties(board_stm32g031_f6_kmx_monitor PROPERTIES LABELS board TIMEOUT 600
  FIXTURES_REQUIRED km_f6_fit_build PASS_REGULAR_EXPRESSION "all checks passed")
# The 32 KiB build's 32-byte application header (board.cmake
# KM_G031_SHORT_HEADER; docs/update.md §2) on the virtual G031, in the
# 64 KiB layout built with it in its own directory: the image's header and
# link address, the bootloader starting it without writing VTOR, and the
# two header formats refusing each other's images (the 256-byte one from
# the stm32g031 preset's build): about 1 min.
add_test(NAME board_stm32g031_short_header
  COMMAND ${KM_DEBIAN_PYTHON} ${KM_ROOT_DIR}/tests/footprint/short_header.py ${KM_ROOT_DIR}
          ${CMAKE_BINARY_DIR}/short-header ${KM_ROOT_DIR}/build/stm32g031)
set_tests_properties(board_stm32g031_short_header PROPERTIES LABELS board TIMEOUT 900)
set_property(TEST board_stm32g031_short_header APPEND PROPERTY ENVIRONMENT_MODIFICATION
  "PYTHONPATH=path_list_append:${KM_ROOT_DIR}/sim/g031")  # the virtual G031
