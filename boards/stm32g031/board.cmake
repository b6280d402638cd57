# STM32G031 (Cortex-M0+) flags for every object of this build: the core,
# one section per function/object so --gc-sections drops what is unused,
# newlib-nano without the C start-up files (startup.c is ours) and no heap.
# -fstack-usage: a .su file per object, the frames tools/image-check sums
# over the call graph to bound the stack.
set(KM_CPU_FLAGS -mcpu=cortex-m0plus -mthumb)
add_compile_options(${KM_CPU_FLAGS} -ffunction-sections -fdata-sections -fstack-usage)
add_link_options(${KM_CPU_FLAGS} --specs=nano.specs --specs=nosys.specs
                 -nostartfiles -Wl,--gc-sections)
