# SPDX-License-Identifier: Apache-2.0
# Firmware update end to end on QEMU (docs/update.md): three servos booting
# through the bootloader on sim/bus/servo-bus, a wrong-model image refused,
# v2 by one broadcast pass, back to v1 with 3 restart frames and 4 real
# system resets (QEMU monitor, sim/bus/servo-bus --monitor-dir) at random
# points. About 40 s; RUN_SERIAL like the other bus tests. tools/servo-update
# --resets 55 is the long run (docs/update.md §11 gives its figures).
# The images come from the qemu-microbit board's build tree (KM_BUILD_DIR_qemu_microbit,
# as tests/qemu.cmake; passed on to the tests and the servo-bus they start).
find_program(KM_PYTHON3_UPD python3)
km_board_build_dir(qemu-microbit dir preset)
set(KM_BUILD_DIR_qemu_microbit ${dir} CACHE PATH "qemu-microbit build read by the QEMU tests")
if(KM_PYTHON3_UPD)
  add_test(NAME update_qemu_e2e
    COMMAND ${KM_PYTHON3_UPD} ${CMAKE_SOURCE_DIR}/tests/qemu/update_e2e.py --restarts 3 --resets 4)
  set_tests_properties(update_qemu_e2e PROPERTIES LABELS bus TIMEOUT 300 RUN_SERIAL TRUE
    PASS_REGULAR_EXPRESSION "all checks passed"
    ENVIRONMENT "KM_BUILD_DIR_qemu_microbit=${KM_BUILD_DIR_qemu_microbit}")
endif()

# servo-update stopped half way (issue 18 item 6): an absent ID refused with
# both QEMU bootloader servos untouched, then Ctrl-C in the middle of the
# blocks: the command it prints finishes the update (tests/tools/
# servo_update_qemu.py: unittest, not in py_tools' discovery). About 15 s.
if(KM_PYTHON3_UPD)
  add_test(NAME update_qemu_interrupt
    COMMAND ${KM_PYTHON3_UPD} ${CMAKE_SOURCE_DIR}/tests/tools/servo_update_qemu.py -v)
  set_tests_properties(update_qemu_interrupt PROPERTIES LABELS bus TIMEOUT 300 RUN_SERIAL TRUE
    FAIL_REGULAR_EXPRESSION "Ran 0 tests;FAILED")
endif()

# A bad image does not brick a servo (docs/update.md §3a): the hang and the
# crash image (tests/qemu/trial/bad_image.c) to two servos by
# tools/servo-update; both back in update mode on their IDs within 30 s,
# then a good image in one pass. About 70 s; RUN_SERIAL like the others.
if(KM_PYTHON3_UPD)
  add_test(NAME update_qemu_trial
    COMMAND ${KM_PYTHON3_UPD} ${CMAKE_SOURCE_DIR}/tests/qemu/update_trial.py)
  set_tests_properties(update_qemu_trial PROPERTIES LABELS bus TIMEOUT 300 RUN_SERIAL TRUE
    PASS_REGULAR_EXPRESSION "all checks passed"
    ENVIRONMENT "KM_BUILD_DIR_qemu_microbit=${KM_BUILD_DIR_qemu_microbit}")
endif()
