# Firmware update end to end on QEMU (docs/update.md): three servos booting
# through the bootloader on tools/servo-bus, a wrong-model image refused,
# v2 by one broadcast pass, back to v1 with 6 restarts at random points.
# About 40 s; RUN_SERIAL like the other bus tests. tests/qemu/update_e2e.py
# --restarts 50 is the long run (docs/update.md gives its figures).
find_program(KM_PYTHON3_UPD python3)
if(KM_PYTHON3_UPD)
  add_test(NAME update_qemu_e2e
    COMMAND ${KM_PYTHON3_UPD} ${CMAKE_SOURCE_DIR}/tests/qemu/update_e2e.py --restarts 6)
  set_tests_properties(update_qemu_e2e PROPERTIES LABELS bus TIMEOUT 300 RUN_SERIAL TRUE
    PASS_REGULAR_EXPRESSION "all checks passed")
endif()
