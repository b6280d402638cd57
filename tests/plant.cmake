# The plant tests compute expected physics with libm on the host (the plant
# itself is integer-only).
if(TARGET test_plant)
  target_link_libraries(test_plant PRIVATE m)
endif()
