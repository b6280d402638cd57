# km_stm32_add_image(<target>): link an executable with the board's linker
# script and emit <target>.elf/.bin/.hex/.map plus an arm-none-eabi-size
# report. Stand-in for the shared km_add_image() until the two are unified.
function(km_stm32_add_image target)
  set(ld ${KM_BOARD_DIR}/stm32g031.ld)
  set_target_properties(${target} PROPERTIES SUFFIX ".elf" LINK_DEPENDS ${ld})
  target_link_options(${target} PRIVATE -T${ld}
                      -Wl,-Map=$<TARGET_FILE_DIR:${target}>/${target}.map
                      -Wl,--print-memory-usage)
  add_custom_command(TARGET ${target} POST_BUILD
    COMMAND ${CMAKE_OBJCOPY} -O binary $<TARGET_FILE:${target}> $<TARGET_FILE_DIR:${target}>/${target}.bin
    COMMAND ${CMAKE_OBJCOPY} -O ihex $<TARGET_FILE:${target}> $<TARGET_FILE_DIR:${target}>/${target}.hex
    COMMAND ${CMAKE_SIZE} $<TARGET_FILE:${target}>
    VERBATIM)
endfunction()
