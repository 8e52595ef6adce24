# semlio_run: the odometry on any input (examples/run/). The bag formats come
# with the optional semlio::io_bags component (cmake/SemlioBags.cmake).
# semlio_run_tool: the run itself (odometry_tool.hpp's run_tool), compiled
# once and linked by semlio_run and semlio_kitti.
add_library(semlio_run_tool OBJECT run/odometry_tool.cpp)
target_link_libraries(semlio_run_tool PUBLIC semlio::semlio CLI11::CLI11 yaml-cpp)
target_include_directories(semlio_run_tool PUBLIC "${CMAKE_CURRENT_SOURCE_DIR}/run" "${CMAKE_CURRENT_SOURCE_DIR}/kitti"
                                                  "${CMAKE_CURRENT_SOURCE_DIR}/common")
semlio_set_warnings(semlio_run_tool)
# --labels onnx: the optional ONNX segmenter (cmake/SemlioOnnx.cmake); its
# SEMLIO_HAVE_ONNX=1 reaches semlio_run and semlio_kitti through this link.
if(SEMLIO_HAVE_ONNX)
  target_link_libraries(semlio_run_tool PUBLIC semlio::segment_onnx)
endif()

semlio_add_example(semlio_run run/semlio_run.cpp)
target_link_libraries(semlio_run PRIVATE semlio_run_tool)
if(SEMLIO_HAVE_BAGS)
  target_link_libraries(semlio_run PRIVATE semlio::io_bags)
  target_compile_definitions(semlio_run PRIVATE SEMLIO_HAVE_BAGS)
endif()
