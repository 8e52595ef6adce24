# Examples of the sim area.
semlio_add_example(semlio_simulate sim/semlio_simulate.cpp)
# --bag / --mcap need the bag writers' libraries (cmake/SemlioBags.cmake).
if(SEMLIO_HAVE_BAGS)
  target_link_libraries(semlio_simulate PRIVATE semlio::io_bags)
  target_compile_definitions(semlio_simulate PRIVATE SEMLIO_SIMULATE_BAGS=1)
else()
  target_compile_definitions(semlio_simulate PRIVATE SEMLIO_SIMULATE_BAGS=0)
endif()
