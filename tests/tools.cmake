# SPDX-License-Identifier: Apache-2.0
# Python tests of the host tools (the frame codec kmx.frame, sim/bus/servo-bus) and the host
# package host/kmx (test_kmx.py: codec, registers, transports, Bus against a
# real host-sim servo over TCP and a pty and on the 3-servo host-sim bus of
# servo-bus, about 3 s; test_kmx_cli.py: the kmx command
# against host-sim and the 3-servo bus, with tools/servo-session, about 14 s;
# test_kmx_baud.py: the baud model (sim/bus/kmwire.py, host-sim --baud,
# servo-bus over RFC 2217) and kmx set-baud, scan --all-bauds, rescue on two
# host-sim servos, about 23 s; test_servo_bus_stop.py: Ctrl-C at random
# moments of servo-bus's start-up, 20 runs on host-sim and 20 on QEMU (when
# built) with no process left (tests/tools/ctrl_c_check.py, by PID), a
# signal at the last moments of start-up ends it without "ready", a Ctrl-C
# that reaches the board query too, host-sim servos starting while every
# port servo-bus releases is taken, SIGKILL, --flash-dir relaunch, one-line
# refusals, about 20 s; test_kmx_shared_id.py:
# every path that writes an ID refuses a taken or shared one, scan flags an ID
# two servos answer on and its command separates them, about 10 s;
# test_kmx_url_ctrl_c.py: rfc2217:// and socket:// buses, Ctrl-C anywhere in
# kmx (16 runs interrupted at random), about 15 s; test_servo_update.py:
# servo-update's one-line refusals and its checks before touching a servo,
# about 5 s; test_kmx_update.py: the same through `kmx update`, `kmx trace`
# and `kmx --trace`'s decoded answers, about 8 s; test_kmx_transport.py: device
# paths, loop://, spy://, hwgrep://, socket:// through pyserial, about 6 s;
# test_kmx_limits.py: product bounds and angle limits named before sending,
# products.json current, about 4 s; test_kmx_web_api.py: kmx web's JSON API
# without a browser (needs python3-aiohttp), the bench of servo-bus
# --inject-dir (a supply sag trips and releases the voltage protection),
# Ctrl-C at 10 random moments with requests in flight, about 30-60 s; test_kmx_bench.py: the bench reaches a servo at the ID it
# answers at after set-id, refuses a shared ID, about 12 s; test_servo_bus_sched.py: SCHED_FIFO by default where allowed,
# --no-realtime, the fallback, policies read back from the kernel, three
# QEMU servos in the polling update bootloader put back to plain scheduling
# and answering, a busy-looping process made plain within 0.5 s, a bootloader
# image's servos at priority 9, below the rest, about 10 s; test_run_on_bus.py: the conformance wrapper runs every check it
# names, on a SCHED_FIFO and a plain bus, and counts a check not run as a
# failure, about 12 s; all need the host-sim preset built). Whole py_tools
# run: 178-245 s measured on the shared 2-core machine with other builds running
# (load average 11-14), with the kmx tests of issue 23.
# unittest exits non-zero when any test fails or errors, which fails the CTest test;
# FAIL_REGULAR_EXPRESSION also catches a run that collected no tests at all.
find_program(KM_PYTHON3 python3)
if(KM_PYTHON3)
  add_test(NAME py_tools
    COMMAND ${KM_PYTHON3} -m unittest discover -s ${CMAKE_SOURCE_DIR}/tests/tools -v)
  set_tests_properties(py_tools PROPERTIES
    LABELS tools TIMEOUT 900
    FAIL_REGULAR_EXPRESSION "Ran 0 tests;FAILED")
  # test_run_on_bus.py also imports the conformance wrapper (tests/conformance/)
  set_property(TEST py_tools APPEND PROPERTY ENVIRONMENT_MODIFICATION
    "PYTHONPATH=path_list_append:${CMAKE_SOURCE_DIR}/tests/conformance")
  # tools/gen/reg-hooks (protocol/'s hook lists, generated in every build)
  # on its own, about 2 s: its headers compiled and their lists printed.
  add_test(NAME reg_hooks_gen
    COMMAND ${KM_PYTHON3} ${CMAKE_SOURCE_DIR}/tests/tools/test_reg_hooks.py -v)
  set_tests_properties(reg_hooks_gen PROPERTIES
    LABELS "tools;unit" TIMEOUT 120
    FAIL_REGULAR_EXPRESSION "Ran 0 tests;FAILED")
endif()

# host/ installs with pip from the checkout without network, into a venv of
# Debian's python3 that sees python3-serial, as a real install (registers.json
# and products.json read from site-packages) and editable; a venv of another
# python3 on PATH too; the installed kmx command runs
# (tests/tools/kmx_install_check.sh, 30-140 s with the machine loaded).
if(EXISTS /usr/bin/python3)
  add_test(NAME kmx_pip_install COMMAND sh ${CMAKE_SOURCE_DIR}/tests/tools/kmx_install_check.sh)
  set_tests_properties(kmx_pip_install PROPERTIES LABELS tools TIMEOUT 400
    PASS_REGULAR_EXPRESSION "kmx_pip_install: ok")
endif()

# The example scripts of docs/python-api.md (host/examples/) run against three
# host-sim servos on sim/bus/servo-bus and print what the tutorial says
# (tests/tools/kmx_examples_check.py; needs the host-sim preset), about 10 s.
if(KM_PYTHON3)
  add_test(NAME kmx_examples COMMAND ${KM_PYTHON3} ${CMAKE_SOURCE_DIR}/tests/tools/kmx_examples_check.py -v)
  set_tests_properties(kmx_examples PROPERTIES LABELS tools TIMEOUT 300
    FAIL_REGULAR_EXPRESSION "Ran 0 tests;FAILED")
endif()

# kmx web in Debian's Chromium, headless, through Selenium: scan, an edit read
# back, a refused value's limit, a move on the live plot (its rate keeping the
# 20 Hz schedule or what one sample's time allows), set-id refused on a
# taken ID, set-baud then the page's rescue finding the servo at its new baud,
# the bench tripping and releasing a temperature protection (three host-sim
# servos), an update to its end state (two QEMU bootloader servos) and a rescue
# update of a QEMU servo left in update mode (needs the qemu preset);
# screenshots into docs/web/. Exit 77 = skipped, with the reason, when
# chromium, chromium-driver or python3-selenium is missing (tools/install-deps).
# tests/tools/kmx_web_check.py, 1.5-4 min on the loaded 2-core machine.
if(EXISTS /usr/bin/python3)
  add_test(NAME kmx_web COMMAND /usr/bin/python3 ${CMAKE_SOURCE_DIR}/tests/tools/kmx_web_check.py -v)
  set_tests_properties(kmx_web PROPERTIES LABELS tools TIMEOUT 900 RUN_SERIAL TRUE SKIP_RETURN_CODE 77
    FAIL_REGULAR_EXPRESSION "Ran 0 tests;FAILED")
endif()
