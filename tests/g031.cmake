# Virtual STM32G031 tests (host preset, label g031): the emulator in
# sim/g031 on Debian's python3-unicorn runs the images the stm32g031 preset
# built, so that preset must be built first in the same tree; missing
# images fail the test with that advice. Debian's /usr/bin/python3 is used
# because python3-unicorn and python3-pyelftools are installed for it.
set(KM_G031_IMAGES ${CMAKE_SOURCE_DIR}/build/stm32g031/boards/stm32g031)
find_program(KM_DEBIAN_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(KM_DEBIAN_PYTHON)
  execute_process(COMMAND ${KM_DEBIAN_PYTHON} -c "import unicorn, elftools"
                  RESULT_VARIABLE KM_G031_PY_OK OUTPUT_QUIET ERROR_QUIET)
endif()
if(KM_DEBIAN_PYTHON AND KM_G031_PY_OK EQUAL 0)
  add_test(NAME g031_periph_models
    COMMAND ${KM_DEBIAN_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/g031/test_g031_periph.py)
  set_tests_properties(g031_periph_models PROPERTIES LABELS g031)
  foreach(t test_standalone_image_reaches_main_loop test_bootloader_starts_app_to_main_loop
            test_ping_and_register_read_answered test_hung_main_loop_ends_in_iwdg_reset
            test_register_write_survives_system_reset)
    string(REPLACE "test_" "g031_" name ${t})
    add_test(NAME ${name}
      COMMAND ${KM_DEBIAN_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/g031/test_vg031_images.py
              ${KM_G031_IMAGES} Images.${t})
    set_tests_properties(${name} PROPERTIES LABELS g031 TIMEOUT 600)
  endforeach()
else()
  message(WARNING "/usr/bin/python3 with unicorn and elftools missing (tools/install-deps): g031 tests not registered")
endif()
