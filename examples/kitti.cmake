# Examples of the kitti area. semlio_kitti runs semlio_run's code
# (semlio_run_tool, examples/run.cmake) on a KITTI-layout folder.
find_package(CLI11 REQUIRED)
find_package(yaml-cpp REQUIRED)
semlio_add_example(semlio_kitti kitti/main_semlio_kitti.cpp)
target_link_libraries(semlio_kitti PRIVATE semlio_run_tool)
