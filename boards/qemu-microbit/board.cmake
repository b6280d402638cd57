# qemu-microbit board flags (included before any library, so every object of
# this build is compiled for the nRF51822's Cortex-M0).
set(KM_CPU_FLAGS -mcpu=cortex-m0 -mthumb)
# -fstack-usage: a .su file per object, to bound the 2 KiB stack by reading.
add_compile_options(${KM_CPU_FLAGS} -ffunction-sections -fdata-sections -fstack-usage)
# newlib-nano for memcpy/memset only; our own startup (no crt0) and no
# nosys.specs, so anything reaching for syscalls or a heap fails to link.
add_link_options(${KM_CPU_FLAGS} --specs=nano.specs -nostartfiles -Wl,--gc-sections)
include(${CMAKE_SOURCE_DIR}/cmake/km_image.cmake)

# The UART's gap floor (QEMU delivers bytes when the host schedules it) is
# a run-time option, a RAM word set by -device loader: see uart.c.
