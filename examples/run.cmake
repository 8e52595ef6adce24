# semlio_run: the odometry on any input (examples/run/). The bag formats come
# with the optional semlio::io_bags component (cmake/SemlioBags.cmake).
semlio_add_example(semlio_run run/semlio_run.cpp)
target_include_directories(semlio_run PRIVATE "${CMAKE_CURRENT_SOURCE_DIR}/run" "${CMAKE_CURRENT_SOURCE_DIR}/kitti")
target_link_libraries(semlio_run PRIVATE CLI11::CLI11 yaml-cpp)
if(SEMLIO_HAVE_BAGS)
  target_link_libraries(semlio_run PRIVATE semlio::io_bags)
  target_compile_definitions(semlio_run PRIVATE SEMLIO_HAVE_BAGS)
endif()
