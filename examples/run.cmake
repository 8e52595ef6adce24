# semlio_run: the odometry on any input (examples/run/). The bag formats come
# with the optional semlio::io_bags component (cmake/SemlioBags.cmake).
# semlio_run_tool: the run itself (odometry_tool.hpp's run_tool) and the two
# tools' command lines (tool_mains.hpp), compiled as one translation unit
# (unity build) and linked by semlio_run and semlio_kitti, whose main()s only
# call in: GCC instantiates the pipelines' templates once instead of three
# times (each of the three files took 165-235 s of CPU on its own).
# odometry_tool.cpp comes first: it defines SEMLIO_RUN_TOOL_DEFINITION before
# the first include of odometry_tool.hpp.
add_library(semlio_run_tool OBJECT run/odometry_tool.cpp run/semlio_run.cpp kitti/semlio_kitti.cpp)
set_target_properties(semlio_run_tool PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 0)
target_link_libraries(semlio_run_tool PUBLIC semlio::semlio CLI11::CLI11 yaml-cpp)
target_include_directories(semlio_run_tool PUBLIC "${CMAKE_CURRENT_SOURCE_DIR}/run" "${CMAKE_CURRENT_SOURCE_DIR}/kitti"
                                                  "${CMAKE_CURRENT_SOURCE_DIR}/common")
semlio_set_warnings(semlio_run_tool)
# --labels onnx: the optional ONNX segmenter (cmake/SemlioOnnx.cmake); its
# SEMLIO_HAVE_ONNX=1 reaches semlio_run and semlio_kitti through this link.
if(SEMLIO_HAVE_ONNX)
  target_link_libraries(semlio_run_tool PUBLIC semlio::segment_onnx)
endif()

if(SEMLIO_HAVE_BAGS)
  target_link_libraries(semlio_run_tool PUBLIC semlio::io_bags)
  target_compile_definitions(semlio_run_tool PRIVATE SEMLIO_HAVE_BAGS)
endif()

semlio_add_example(semlio_run run/main_semlio_run.cpp)
target_link_libraries(semlio_run PRIVATE semlio_run_tool)
