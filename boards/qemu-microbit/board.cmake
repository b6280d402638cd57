# qemu-microbit board flags (included before any library, so every object of
# this build is compiled for the nRF51822's Cortex-M0).
set(KM_CPU_FLAGS -mcpu=cortex-m0 -mthumb)
# -fstack-usage: a .su file per object, to bound the 2 KiB stack by reading.
add_compile_options(${KM_CPU_FLAGS} -ffunction-sections -fdata-sections -fstack-usage)
# newlib-nano for memcpy/memset only; our own startup (no crt0) and no
# nosys.specs, so anything reaching for syscalls or a heap fails to link.
add_link_options(${KM_CPU_FLAGS} --specs=nano.specs -nostartfiles -Wl,--gc-sections)
include(${CMAKE_SOURCE_DIR}/cmake/km_image.cmake)

# QEMU delivers UART bytes when the host schedules it: a frame may pause
# for milliseconds mid-way (see KM_APP_GAP_MIN_US in firmware/app/km_app.c).
add_compile_definitions(KM_APP_GAP_MIN_US=20000u)
