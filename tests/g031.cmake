# SPDX-License-Identifier: Apache-2.0
# Virtual STM32G031 tests (host preset, label g031): the emulator in
# sim/g031 on Debian's python3-unicorn runs the images the stm32g031 preset
# built, so that preset must be built first in the same tree; missing
# images fail the test with that advice. Debian's /usr/bin/python3 is used
# because tools/install-deps installs python3-unicorn and python3-pyelftools
# for it. The tests are registered whatever this machine has: a missing
# module fails each of them with the install advice (sim/g031/g031_deps.py),
# and a missing /usr/bin/python3 fails the one test below.
set(KM_G031_IMAGES ${CMAKE_SOURCE_DIR}/build/stm32g031/boards/stm32g031)
find_program(KM_DEBIAN_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT KM_DEBIAN_PYTHON)
  add_test(NAME g031_debian_python
    COMMAND ${CMAKE_COMMAND} "-DKM_MSG=/usr/bin/python3 missing: run tools/install-deps (python3, python3-unicorn, python3-pyelftools)"
            -P ${CMAKE_CURRENT_SOURCE_DIR}/g031/fail.cmake)
  set_tests_properties(g031_debian_python PROPERTIES LABELS g031)
  return()
endif()
add_test(NAME g031_periph_models
  COMMAND ${KM_DEBIAN_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/g031/test_g031_periph.py)
set_tests_properties(g031_periph_models PROPERTIES LABELS g031)
add_test(NAME g031_regs_header_matches_svd
  COMMAND ${KM_DEBIAN_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/g031/test_g0_regs_vs_svd.py)
set_tests_properties(g031_regs_header_matches_svd PROPERTIES LABELS g031)
foreach(t test_standalone_image_reaches_main_loop test_bootloader_starts_app_to_main_loop
          test_ping_and_register_read_answered test_hung_main_loop_ends_in_iwdg_reset
          test_register_write_survives_system_reset test_no_unaligned_access_through_boot_and_bus
          test_first_sensor_read_after_a_full_adc_scan test_received_byte_reaches_rx_queue
          test_byte_inside_a_frame_runs_no_main_loop test_tick_inside_a_frame_leaves_only_a_short_rest_queued
          test_framing_error_drops_its_frame_then_bytes_flow
          test_hardfault_frees_bridge_and_leaves_record test_stack_guard_written_resets_with_record
          test_update_mode_bootloader_sleeps_between_bytes
          test_master_pause_exact_on_the_wire)
  string(REPLACE "test_" "g031_" name ${t})
  add_test(NAME ${name}
    COMMAND ${KM_DEBIAN_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/g031/test_vg031_images.py
            ${KM_G031_IMAGES} Images.${t})
  set_tests_properties(${name} PROPERTIES LABELS g031 TIMEOUT 600)
endforeach()
# Flash work and the bus, and the stack's measured high-water mark
# (tests/g031/test_vg031_flash.py; docs/store.md "Preparing in idle time").
add_test(NAME g031_first_saved_setting_ping_on_time
  COMMAND ${KM_DEBIAN_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/g031/test_vg031_flash.py
          ${KM_G031_IMAGES} Flash.test_first_saved_setting_after_idle_format_ping_on_time)
set_tests_properties(g031_first_saved_setting_ping_on_time PROPERTIES LABELS g031 TIMEOUT 600)
# A ping during each kind of flash operation: bytes lost and answer delay
# (docs/virtual-g031.md "Flash work and the bus").
add_test(NAME g031_ping_during_flash_operations
  COMMAND ${KM_DEBIAN_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/g031/test_vg031_flash.py
          ${KM_G031_IMAGES} Flash.test_ping_during_each_kind_of_flash_operation)
set_tests_properties(g031_ping_during_flash_operations PROPERTIES LABELS g031 TIMEOUT 600)
# The bus suites on three virtual G031s (servo-bus --backend g031: one
# process, one wire in virtual time, sim/g031/vg031_bus.py) at 115200 baud,
# with the master on the bus's virtual time (servo-bus --clock-file, the
# master under sim/g031/vclock.py): every timeout and pause of the suite and
# of kmx update counts the servos' time, however slow the emulator or loaded
# the host (docs/virtual-g031.md "Virtual time for the master"). The answer
# slots are exact in virtual time, so every check runs in one pass at 115200
# without a slot floor (the image has none) and without SCHED_FIFO.
# g031_conformance: all 182 checks of the suite on the unmodified
# stand-alone km-servo-stm32g031.elf (as the QEMU conformance runs its
# stand-alone image: with the bootloader, the suite's restarts, closer
# together in virtual time than 1 s, use up the boot trial and leave a servo
# in update mode, docs/update.md §3a).
# g031_update_on_bus: tests/g031/update_on_bus.py, the bootloader + .kmfw
# pair: a wrong-model image refused by all three, the v2 build
# (km-servo-app-v2-stm32g031.kmfw) in one broadcast pass, back to v1 with
# restarts and NRST resets mid-update.
# RUN_SERIAL: one core for the three servos, the other for the master.
find_program(KM_PYTHON3_G031BUS python3)
if(KM_PYTHON3_G031BUS)
  add_test(NAME g031_conformance
    COMMAND ${KM_PYTHON3_G031BUS} ${CMAKE_SOURCE_DIR}/tests/conformance/run_on_bus.py
            --backend g031 --slot-timing plain --virtual-time
            --image ${KM_G031_IMAGES}/km-servo-stm32g031.elf -- --load 1000)
  set_tests_properties(g031_conformance PROPERTIES LABELS "g031;conformance;bus" TIMEOUT 1500 RUN_SERIAL TRUE)
endif()
add_test(NAME g031_update_on_bus
  COMMAND ${KM_DEBIAN_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/g031/update_on_bus.py
          --build-stm32 ${CMAKE_SOURCE_DIR}/build/stm32g031)
# g031_bus_protect: tests/bus/bus_check.py protect (the protection
# supervisor with the bench scenario tests/bus/scenarios/protect.txt, about
# 50 s of the scenario's time) on one virtual G031; bus_check puts itself on
# the bus's virtual time for the g031 backend, so its reaction bounds hold.
add_test(NAME g031_bus_protect
  COMMAND ${KM_DEBIAN_PYTHON} ${CMAKE_SOURCE_DIR}/tests/bus/bus_check.py protect --backend g031)
set_property(TEST g031_bus_protect APPEND PROPERTY ENVIRONMENT_MODIFICATION
  "PYTHONPATH=path_list_append:${CMAKE_SOURCE_DIR}/tests/conformance")  # bus_check's master (tests/bus.cmake)
set_tests_properties(g031_update_on_bus g031_bus_protect PROPERTIES LABELS "g031;bus" TIMEOUT 2400 RUN_SERIAL TRUE
  PASS_REGULAR_EXPRESSION "all checks passed")
# The held-shaft stall of that bench replayed in virtual time on one virtual
# G031, with the 0x65 before it shifted by 0-3 ms (on the bus the master's
# timing moves it from run to run): the bench's hold-phase load must trip
# the stall at every shift (docs/virtual-g031.md "Found: the held-shaft stall
# that did not trip").
add_test(NAME g031_protect_hold_stall_any_phase
  COMMAND ${KM_DEBIAN_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/g031/test_protect_hold_stall.py ${KM_G031_IMAGES})
set_tests_properties(g031_protect_hold_stall_any_phase PROPERTIES LABELS g031 TIMEOUT 900)
# sim/g031 (the emulator, vclock) for every test here, beside the host
# package and sim/bus that tests/CMakeLists.txt gives all tests.
get_property(km_g031_tests DIRECTORY PROPERTY TESTS)
list(FILTER km_g031_tests INCLUDE REGEX "^g031_")
set_property(TEST ${km_g031_tests} APPEND PROPERTY ENVIRONMENT_MODIFICATION
  "PYTHONPATH=path_list_append:${CMAKE_SOURCE_DIR}/sim/g031")
